"""Peer validation of the rigid-body vehicle against RotorPy: max errors and the README figure.

aerodock's ``step_rigid_body`` and RotorPy's ``Multirotor`` fly the same vehicle under the same
rotor-speed commands (recorded from aerodock's autopilot flying a tilting manoeuvre), open loop,
for 5 s at 500 Hz: :mod:`aerodock.validation.peer`. Prints the largest position and attitude
differences with rotor and parasitic drag on and off, and draws both simulators' position and
attitude and their difference over time (the aero-on run) to a PNG.

Needs RotorPy: ``.venv/bin/pip install --no-deps rotorpy``.

Run: ``.venv/bin/python studies/peer_rotorpy.py [--figure docs/figures/peer_rotorpy.png] [--json]
[--rtol 1e-9] [--smoke]``; ``--smoke`` flies 0.2 s with drag on only (its error is no figure).
"""

from __future__ import annotations

import argparse
import io
import sys
from pathlib import Path

import numpy as np
from _smoke import add_smoke_option  # studies/, on sys.path

from aerodock.config import load_config
from aerodock.fileio import atomic_open, dumps_json
from aerodock.validation.peer import (
    TOLERANCE_ATTITUDE_DEG,
    TOLERANCE_POSITION_M,
    PeerComparison,
    compare_with_rotorpy,
)


def draw(comp: PeerComparison, path: Path) -> Path:
    """Position, attitude and their differences over time, both simulators (PNG, ~60 kB)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    a, r = comp.aerodock, comp.rotorpy
    t = a.t_s
    fig, axes = plt.subplots(2, 2, figsize=(9.0, 5.6), sharex=True)
    colours = ("tab:blue", "tab:orange", "tab:green")
    up = np.array([1.0, 1.0, -1.0])  # plot altitude (up) instead of NED down
    for k, name in enumerate(("north", "east", "up")):
        axes[0, 0].plot(t, a.p_m[:, k] * up[k] - a.p_m[0, k] * up[k], color=colours[k],
                        label=f"{name} aerodock")
        axes[0, 0].plot(t, r.p_m[:, k] * up[k] - r.p_m[0, k] * up[k], color=colours[k],
                        ls="--", label=f"{name} RotorPy")
    axes[0, 0].set_ylabel("position from start, m")
    axes[0, 0].legend(fontsize=7, ncol=2)
    ra, rr = np.degrees(a.rpy_rad), np.degrees(r.rpy_rad)
    for k, name in enumerate(("roll", "pitch", "yaw")):
        axes[0, 1].plot(t, ra[:, k], color=colours[k], label=f"{name} aerodock")
        axes[0, 1].plot(t, rr[:, k], color=colours[k], ls="--", label=f"{name} RotorPy")
    axes[0, 1].set_ylabel("attitude, deg")
    axes[0, 1].legend(fontsize=7, ncol=2)
    axes[1, 0].plot(t, comp.position_error_m * 1000.0, color="black")
    axes[1, 0].axhline(TOLERANCE_POSITION_M * 1000.0, color="red", ls=":", label="tolerance")
    axes[1, 0].set_ylabel("|p_aerodock - p_RotorPy|, mm")
    axes[1, 0].legend(fontsize=7)
    axes[1, 1].plot(t, comp.attitude_error_deg, color="black")
    axes[1, 1].set_ylabel("attitude difference, deg")
    axes[1, 1].set_yscale("log")
    axes[1, 1].axhline(TOLERANCE_ATTITUDE_DEG, color="red", ls=":", label="tolerance")
    axes[1, 1].legend(fontsize=7)
    for ax in axes[1]:
        ax.set_xlabel("time, s")
    s = comp.summary()
    fig.suptitle(f"Same vehicle, same rotor commands, open loop at 500 Hz: aerodock vs RotorPy "
                 f"(rotor + parasitic drag {'on' if comp.aero else 'off'})\n"
                 f"max difference {s['max_position_error_m'] * 1000:.2f} mm, "
                 f"{s['max_attitude_error_deg']:.3f} deg", fontsize=9)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=80)
    plt.close(fig)
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_open(path, "wb") as fh:
        fh.write(buf.getvalue())
    return path


def main(argv: list[str] | None = None) -> int:
    """Run both comparisons, print their figures, draw the aero-on one if asked."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--figure", type=Path, help="write the figure (PNG) here")
    parser.add_argument("--json", action="store_true", help="print the figures as JSON")
    parser.add_argument("--rtol", type=float, default=None,
                        help="RotorPy's solve_ivp relative tolerance (default: its own, 1e-3); "
                             "atol is 1e-3 of it")
    add_smoke_option(parser)
    args = parser.parse_args(argv)
    try:
        import rotorpy  # noqa: F401
    except ImportError:
        print("error: RotorPy is not installed (.venv/bin/pip install --no-deps rotorpy)",
              file=sys.stderr)
        return 2
    cfg = load_config()
    if args.rtol is not None and not 0.0 < args.rtol < 1.0:
        parser.error(f"--rtol must be in (0, 1), got {args.rtol}")
    kwargs = (None if args.rtol is None
              else {"method": "RK45", "rtol": args.rtol, "atol": 1e-3 * args.rtol})
    size = {"duration_s": 0.2} if args.smoke else {}
    runs = {aero: compare_with_rotorpy(cfg, aero=aero, integrator_kwargs=kwargs, **size)
            for aero in ((True,) if args.smoke else (True, False))}
    if args.json:
        print(dumps_json({("aero_on" if k else "aero_off"): c.summary()
                          for k, c in runs.items()}))
    else:
        for aero, comp in runs.items():
            s = comp.summary()
            print(f"rotor + parasitic drag {'on ' if aero else 'off'}: over "
                  f"{s['duration_s']:g} s at {s['physics_hz']:g} Hz (tilt up to "
                  f"{s['tilt_max_deg']:.1f} deg, travel {s['travel_m']:.2f} m): max position "
                  f"difference {s['max_position_error_m'] * 1000:.2f} mm (tolerance "
                  f"{TOLERANCE_POSITION_M * 1000:g} mm), max attitude difference "
                  f"{s['max_attitude_error_deg']:.3f} deg (tolerance {TOLERANCE_ATTITUDE_DEG:g} "
                  "deg)")
    if args.figure:
        print(f"figure: {draw(runs[True], args.figure)}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
