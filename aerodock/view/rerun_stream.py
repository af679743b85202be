"""Stream a Track to rerun (optional extra ``aerodock[viz]``: ``rerun-sdk``).

Entities (world frame NED, metres): ``world/leader`` and ``world/follower`` (points and arm
segments), ``world/bar`` and ``world/cables`` where the log has the bar, ``world/force`` (the
predicted force arrow, 0.05 m per m/s²) and the scalar ``gate`` (GateState value), on the
timeline ``flight_time`` (seconds).
"""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from aerodock.fileio import atomic_open, check_writable_target, one_line
from aerodock.view.render import FORCE_SCALE_M_PER_MPS2, Track, _arms


def stream_to_rerun(track: Track, save: str | Path | None = None, spawn: bool = False,
                    app_id: str = "aerodock") -> Path | None:
    """Log ``track`` to rerun: to a ``.rrd`` file (``save``), else to a spawned viewer.

    Raises:
        ValueError: rerun-sdk is not installed, or neither ``save`` nor ``spawn`` is given.
        OSError: ``save`` cannot be written (a bad path, a read-only folder, a full disk, a
            FIFO or a device); any old file at ``save`` is left as it was.
    """
    try:
        import rerun as rr
    except ImportError:
        raise ValueError("streaming to rerun needs rerun-sdk: "
                         "pip install 'aerodock[viz]'") from None
    if save is None and not spawn:
        raise ValueError("give a .rrd file to save to, or spawn a viewer")
    if save is None:
        rec = rr.RecordingStream(app_id)
        rec.spawn()
        _log_track(rr, rec, track)
        return None
    save = Path(save)
    # rerun writes the file itself and reports a failure as RuntimeError: it writes into a
    # temporary folder, and the recording then replaces ``save`` atomically (a failure leaves
    # any old file as it was and becomes an OSError naming the file).
    check_writable_target(save)
    with tempfile.TemporaryDirectory(prefix="aerodock-rrd-") as scratch:
        tmp = Path(scratch) / "recording.rrd"
        try:
            rec = rr.RecordingStream(app_id)
            rec.save(str(tmp))  # the sink is set before anything is logged
            _log_track(rr, rec, track)
            rec.disconnect()
        except RuntimeError as err:
            raise OSError(f"{save}: cannot write the rerun recording ({one_line(err)})") from None
        if not tmp.is_file() or tmp.stat().st_size == 0:
            raise OSError(f"{save}: cannot write the rerun recording (nothing was written)")
        with atomic_open(save, "wb") as fh:
            fh.write(tmp.read_bytes())
    return save


def _log_track(rr: Any, rec: Any, track: Track) -> None:
    """Log every sample of ``track`` to the recording stream ``rec``, then flush it."""
    rec.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_DOWN, static=True)
    for k in range(track.n_samples):
        rec.set_time("flight_time", duration=float(track.t_s[k]))
        for name, p, R in (("leader", track.leader_p[k], _row(track.leader_R, k)),
                           ("follower", track.follower_p[k], _row(track.follower_R, k))):
            rec.log(f"world/{name}", rr.Points3D([p], radii=0.01))
            rec.log(f"world/{name}/arms", rr.LineStrips3D(list(_arms(p, R, track.diagonal_m))))
        if track.bar_p is not None:
            rec.log("world/bar", rr.Points3D([track.bar_p[k]], radii=0.005))
            rec.log("world/cables", rr.LineStrips3D([[track.leader_p[k], track.bar_p[k]]]))
        if track.gate is not None:
            rec.log("gate", rr.Scalars(float(track.gate[k])))
        if track.force_mps2 is not None:
            rec.log("world/force", rr.Arrows3D(origins=[track.follower_p[k]],
                                               vectors=[track.force_mps2[k]
                                                        * FORCE_SCALE_M_PER_MPS2]))
    rec.flush()


def _row(arr: np.ndarray | None, k: int) -> np.ndarray | None:
    return None if arr is None else arr[k]
