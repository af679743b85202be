"""Why docking misses the last tenth: each of ``aerodock targets``' four cells flown with
traces, its outcomes split, and for every trial whose gate closed, where the bar was across the
gate's mouth when the close was commanded and how fast it was moving out of it, docked trials
against the bar's slip-throughs.

    .venv/bin/python studies/slip_throughs.py --model DIR [--config FILE] [--trials 300]
        [--seed 5] [--json] [--smoke]

``--config`` defaults to examples/learnt_wrench.toml and the controller is ours (the targets' row
that meets three of four); ``--model`` is that row's model (a ``so2-wrench`` model, e.g.
``reproduce``'s ``data-wrench/models/final``); without it ours flies with its observer alone.
The cells and their campaign seeds are ``targets``' (``seed + 10 k``). Across the mouth is the
bar's centre relative to the gate's axis (the follower's contact arm, ``mount_height_m`` above
its centre, attitude neglected), perpendicular to the bar; the gate holds a bar within
``aperture / 2`` less its radius of that axis when it finishes closing (the software latency and
the servo's travel after the command). The bar's swing is its horizontal speed relative to the
leader, at the command and half a second before it (a swing it had, or a kick of the contact).
``--smoke``: one cell, a few trials, the mission's waits cut.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from _smoke import SMOKE_TRIALS, add_smoke_option, smoke_config  # studies/, on sys.path

from aerodock.config import load_config
from aerodock.control.profiles import controller_config
from aerodock.experiments.targets import SCENARIOS
from aerodock.fileio import dumps_json, json_ready
from aerodock.learning.runtime import Predictor
from aerodock.mission import MissionSpec, run_campaign
from aerodock.mission.spec import Compensation
from aerodock.world.gripper import GateState

ROOT = Path(__file__).resolve().parents[1]
DIFF_PERIODS = 2  # the relative velocity: positions this many control periods apart
SWING_BEFORE_S = 0.5  # the bar's swing read again this long before the command


def _period_s(trace: dict[str, np.ndarray]) -> float:
    """The trace's control period, s."""
    return float(np.median(np.diff(trace["t_s"])))


def _rate(series: np.ndarray, k: int, i: int, dt: float) -> np.ndarray:
    """Trial ``i``'s rate of ``series`` (periods first) at period ``k``: the difference over
    :data:`DIFF_PERIODS` periods back, per second."""
    return (series[k, i] - series[k - DIFF_PERIODS, i]) / (DIFF_PERIODS * dt)


def across_mouth(trace: dict[str, np.ndarray], mount_m: float) -> tuple[np.ndarray, ...]:
    """Per trial whose gate closed: the period the close began, the bar's offset across the
    gate's mouth then (m, signed), its speed out of the mouth (m/s, positive: away from the
    axis) and the offset when the gate resolved. Trials that never closed hold nan and -1."""
    gate = trace["gate"]
    steps, n = gate.shape
    closing = gate == GateState.CLOSING
    first = np.where(closing.any(axis=0), closing.argmax(axis=0), -1)
    last = np.where(closing.any(axis=0), steps - 1 - closing[::-1].argmax(axis=0), -1)
    rel = trace["bar_p"] - trace["follower_p"]
    rel[..., 2] += mount_m  # NED: the arm is above the centre
    yaw = trace["bar_yaw"]
    across = -np.sin(yaw) * rel[..., 0] + np.cos(yaw) * rel[..., 1]  # perpendicular to the bar
    dt = _period_s(trace)
    offset0 = np.full(n, np.nan)
    outward = np.full(n, np.nan)
    offset1 = np.full(n, np.nan)
    for i in np.nonzero(first >= DIFF_PERIODS)[0]:
        k = first[i]
        offset0[i] = across[k, i]
        outward[i] = np.sign(across[k, i]) * _rate(across, k, i, dt)
        offset1[i] = across[min(last[i] + 1, steps - 1), i]
    return first, offset0, outward, offset1


def swing_speed(trace: dict[str, np.ndarray], first: np.ndarray, before_s: float) -> np.ndarray:
    """Per trial whose gate closed, the bar's horizontal speed relative to the leader (its swing
    on the cables), m/s, ``before_s`` before the close was commanded (nan where the trace does
    not reach back that far)."""
    dt = _period_s(trace)
    swing = trace["bar_p"][..., :2] - trace["leader_p"][..., :2]
    out = np.full(first.shape, np.nan)
    for i in np.nonzero(first >= 0)[0]:
        k = first[i] - int(round(before_s / dt))
        if k >= DIFF_PERIODS:
            out[i] = float(np.hypot(*_rate(swing, k, i, dt)))
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", type=Path, help="the learnt model (default: none, observer)")
    parser.add_argument("--config", type=Path, default=ROOT / "examples" / "learnt_wrench.toml")
    parser.add_argument("--trials", type=int, default=300)
    parser.add_argument("--seed", type=int, default=5)
    parser.add_argument("--json", action="store_true")
    add_smoke_option(parser)
    args = parser.parse_args()
    try:
        cfg = controller_config(load_config(args.config), "ours")
        predictor = Predictor.load(args.model) if args.model else None
    except (OSError, ValueError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    scenarios = SCENARIOS
    if args.smoke:
        cfg, args.trials, scenarios = smoke_config(cfg), SMOKE_TRIALS, SCENARIOS[:1]
    mouth_m = cfg.gripper.aperture_m / 2.0 - cfg.platform.bar_diameter_m / 2.0
    rows = []
    for k, (name, offset, speed, _target) in enumerate(scenarios):
        res = run_campaign(cfg, MissionSpec(
            trials=args.trials, offset_m=offset, leader_speed_mps=speed,
            compensation=Compensation.MODEL if predictor else Compensation.OBSERVER,
            seed=args.seed + 10 * k), predictor, record="trace")
        s = res.summary()
        first, off0, out, off1 = across_mouth(res.trace, cfg.gripper.mount_height_m)
        swing_now = swing_speed(res.trace, first, 0.0)
        swing_before = swing_speed(res.trace, first, SWING_BEFORE_S)
        closed = first >= 0
        row = {"cell": name, "trials": s["trials"], "docked": s["docked"],
               "slip_throughs": s["slip_throughs"], "missed": s["missed"], "aborts": s["aborts"],
               "not_closed": int((~closed).sum()), "mouth_half_width_m": mouth_m}
        for label, sel in (("docked", res.success & closed), ("slipped", res.slipped & closed)):
            if sel.any():
                row[label] = {
                    "trials": int(sel.sum()),
                    "offset_at_command_m": _quantiles(np.abs(off0[sel])),
                    "outward_speed_mps": _quantiles(out[sel]),
                    "left_the_mouth": int((np.abs(off1[sel]) > mouth_m).sum()),
                    "swing_rms_mps": _rms(swing_now[sel]),
                    "swing_rms_before_mps": _rms(swing_before[sel]),
                }
        rows.append(row)
        if not args.json:
            print(f"{name}: {s['docked']}/{s['trials']} docked, {s['slip_throughs']} slipped "
                  f"through, {s['missed']} missed, {s['aborts']} aborted, "
                  f"{row['not_closed']} never closed the gate (mouth +-{100 * mouth_m:.1f} cm)")
            for label in ("docked", "slipped"):
                if label in row:
                    r = row[label]
                    print(f"  {label} ({r['trials']}): across the mouth at the command "
                          f"{_cm(r['offset_at_command_m'])} cm, moving out of it at "
                          f"{_fmt(r['outward_speed_mps'])} m/s (10/50/90 %); "
                          f"bar outside the mouth when the gate resolved: {r['left_the_mouth']}; "
                          f"the bar's swing (rms, relative to the leader) "
                          f"{r['swing_rms_mps']:.2f} m/s, {r['swing_rms_before_mps']:.2f} "
                          f"{SWING_BEFORE_S:g} s before")
    if args.json:
        print(dumps_json(json_ready({"rows": rows})))
    return 0


def _rms(x: np.ndarray) -> float:
    x = x[np.isfinite(x)]
    return float(np.sqrt(np.mean(x ** 2))) if x.size else float("nan")


def _quantiles(x: np.ndarray) -> list[float]:
    return [float(v) for v in np.percentile(x, (10, 50, 90))]


def _cm(q: list[float]) -> str:
    return " / ".join(f"{100 * v:.1f}" for v in q)


def _fmt(q: list[float]) -> str:
    return " / ".join(f"{v:+.2f}" for v in q)


if __name__ == "__main__":
    raise SystemExit(main())
