"""MissionMetrics.measure's compiled part (``measure_rows``) gives the numbers of the NumPy code
it replaced, to the bit: history rows, the terminal window's end, ground contacts, the clearance,
first violations and non-finite states, with NaN, infinities and the tilt's arccos domain ends."""

from __future__ import annotations

import numpy as np
import pytest

from aerodock.geometry import norm_rows, rpy_to_rotmat
from aerodock.jit import NUMPY_LOOPS
from aerodock.mission.metrics import measure_rows

DONE, OPEN = 5, 0


def _numpy(t_s, fol_p, fol_r, lead_p, p_ref, ff, saturated, active, gate, phase, contact, thrust,
           mount, clearance, hist_k, approach_end, min_clear, ground_hit, nan_seen):
    """MissionMetrics.measure's arithmetic as NumPy computed it (hist_k, ground_hit and
    nan_seen updated in place; the new approach_end and min_clear returned)."""
    true_err = fol_p - p_ref
    hist_k[:, 0] = np.abs(true_err[:, 2])
    hist_k[:, 1] = track_err_m = norm_rows(true_err)
    hist_k[:, 2] = 0.0 if ff is None else ff[:, 2]
    hist_k[:, 3] = np.rad2deg(np.arccos(np.minimum(np.maximum(fol_r[:, 2, 2], -1.0), 1.0)))
    hist_k[:, 4] = saturated
    ended = (~active | (gate != OPEN)) & (approach_end > t_s)
    approach_end = np.where(ended, t_s, approach_end)
    live = phase != DONE
    ground_hit |= contact & live
    arm = fol_p - fol_r[:, :, 2] * mount
    was_clear = min_clear >= clearance
    min_clear = np.where(live, np.minimum(min_clear, norm_rows(arm - lead_p)), min_clear)
    violated_now = was_clear & (min_clear < clearance)
    nan_seen |= ~(np.isfinite(fol_p).all(axis=1) & np.isfinite(lead_p).all(axis=1)
                  & np.isfinite(thrust))
    return track_err_m, violated_now, live, approach_end, min_clear


def _inputs(rng, n):
    fol_r = rpy_to_rotmat(rng.uniform(-3, 3, (n, 3)))
    fol_r[::5, 2, 2] = rng.choice([1.0, -1.0, np.nextafter(1, 2), np.nextafter(-1, -2), 1.5,
                                   np.nan, -0.0], fol_r[::5, 2, 2].shape)
    fol_p = rng.normal(0, 1, (n, 3))
    lead_p = fol_p + rng.normal(0, 0.3, (n, 3))
    fol_p[::9, rng.integers(3)] = rng.choice([np.nan, np.inf, -np.inf])
    lead_p[::11, rng.integers(3)] = np.nan
    thrust = rng.normal(0.3, 0.1, n)
    thrust[::13] = np.inf
    return dict(t_s=float(rng.uniform(0, 3)), fol_p=fol_p, fol_r=fol_r, lead_p=lead_p,
                p_ref=fol_p + rng.normal(0, 0.1, (n, 3)), ff=rng.normal(0, 1, (n, 3)),
                saturated=rng.random(n) < 0.3, active=rng.random(n) < 0.7,
                gate=rng.integers(0, 3, n).astype(np.int8),
                phase=rng.choice([0, 1, 2, DONE], n).astype(np.int8),
                contact=rng.random(n) < 0.2, thrust=thrust, mount=0.05, clearance=0.25,
                hist_k=np.full((n, 5), np.nan), approach_end=rng.uniform(0, 3, n),
                min_clear=np.where(rng.random(n) < 0.2, np.inf, rng.uniform(0, 0.6, n)),
                ground_hit=rng.random(n) < 0.1, nan_seen=rng.random(n) < 0.1)


@pytest.mark.parametrize("n", [1, 2, 7, 256])
@pytest.mark.parametrize("with_ff", [True, False])
def test_measure_rows_is_numpys(n, with_ff):
    rng = np.random.default_rng(n + 1000 * with_ff)
    for _ in range(4):
        a = _inputs(rng, n)
        if not with_ff:
            a["ff"] = None
        b = {k: v.copy() if isinstance(v, np.ndarray) else v for k, v in a.items()}
        with np.errstate(invalid="ignore"):
            want = _numpy(**a)
        got = (np.empty(n), np.empty(n, dtype=bool), np.empty(n, dtype=bool), np.empty(n),
               np.empty(n))
        measure_rows(NUMPY_LOOPS, b["t_s"], b["fol_p"], b["fol_r"], b["lead_p"], b["p_ref"],
                     with_ff, b["fol_p"] if b["ff"] is None else b["ff"], b["saturated"],
                     b["active"], b["gate"], OPEN, b["phase"], DONE, b["contact"], b["thrust"],
                     b["mount"], b["clearance"], b["hist_k"], b["approach_end"],
                     b["min_clear"], got[3], got[4], b["ground_hit"], b["nan_seen"], got[0],
                     got[1], got[2])
        for w, g in zip(want, got, strict=True):
            assert g.tobytes() == w.tobytes()
        for key in ("hist_k", "ground_hit", "nan_seen", "approach_end", "min_clear"):
            assert b[key].tobytes() == a[key].tobytes(), key  # the last two: not written
