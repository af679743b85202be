"""The paper's controller, step by step from the reproduction's old baseline to the published one
(and onto the world that knows only what a real vehicle knows): docks with and without a model.

    .venv/bin/python studies/baseline_ladder.py --model DIR [--trials 40] [--seed 3] [--json]
        [--smoke]

Each row adds one difference to the row above; every row flies the same trials (same seed).
``--smoke`` flies the last row only, two trials each, the mission's waits cut.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from _smoke import SMOKE_TRIALS, add_smoke_option, smoke_config  # studies/, on sys.path

from aerodock.config import load_config
from aerodock.control.compensation import Compensation
from aerodock.control.profiles import PAPER_Q_DIAG, PAPER_R_DIAG
from aerodock.learning.runtime import Predictor
from aerodock.mission import MissionSpec, run_campaign

SPREADS = ("mass_sd", "inertia_sd", "torque_coeff_sd", "motor_tau_sd")
OLD_PAPER = {"control": {"q_diag": list(PAPER_Q_DIAG), "r_diag": list(PAPER_R_DIAG),
                         "terminal_q_diag": list(PAPER_Q_DIAG),
                         "terminal_r_diag": list(PAPER_R_DIAG), "observer_bias_tau_s": 4.0,
                         "rejection": "bias-observer", "torque_feedforward": False},
             "imu": {"chain": "ideal"}, "mission": {"gate_state_from": "truth"},
             "vehicle": dict.fromkeys(SPREADS, 0.0)}
STEPS = [
    ("old reproduction: 4 s time-constant observer, 100 Hz, full reference feed-forward", {}),
    ("+ Freyja's bias estimator (20 Hz propagation)", {"control": {"bias_estimator": "freyja"}}),
    ("+ Freyja's state filter (position and velocity)", {"control": {"state_filter": "freyja"}}),
    ("+ controller at 50 Hz", {"control": {"command_rate_hz": 50.0}}),
    ("+ no reference acceleration feed-forward (published)",
     {"control": {"reference_ff_factor": 0.0}}),
    ("+ IMU chain and attitude estimate", {"imu": {"chain": "filtered"}}),
    ("+ gate known by its sensors", {"mission": {"gate_state_from": "sensors"}}),
    ("+ each vehicle apart from its nominal constants (the default world)", "spreads"),
    ("then: the estimator handed the whole command, the learnt feed-forward included "
     "(the other reading of the unstated patch)",
     {"control": {"freyja_estimator_input": "command"}}),
]


def _merge(a: dict, b: dict) -> dict:
    out = {k: dict(v) for k, v in a.items()}
    for k, v in b.items():
        out.setdefault(k, {}).update(v)
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", type=Path, required=True)
    parser.add_argument("--trials", type=int, default=40)
    parser.add_argument("--seed", type=int, default=3)
    parser.add_argument("--config", type=Path, default=None)
    parser.add_argument("--json", action="store_true")
    add_smoke_option(parser)
    args = parser.parse_args()
    base = load_config(args.config)
    if args.smoke:
        base, args.trials = smoke_config(base), SMOKE_TRIALS
    predictor = Predictor.load(args.model)
    overrides, rows = OLD_PAPER, []
    for i, (name, step) in enumerate(STEPS):
        if step == "spreads":  # the configuration's own spreads (the defaults: a real fleet's)
            step = {"vehicle": {k: getattr(base.vehicle, k) for k in SPREADS}}
        overrides = _merge(overrides, step)
        if args.smoke and i < len(STEPS) - 1:
            continue  # the steps still add up
        cfg = base.with_overrides(overrides)
        row = {"step": name}
        for label, comp in (("with_model", Compensation.MODEL),
                            ("without_model", Compensation.OBSERVER)):
            res = run_campaign(cfg, MissionSpec(trials=args.trials, seed=args.seed,
                                                offset_m=0.36, compensation=comp),
                               predictor if comp == Compensation.MODEL else None)
            s = res.summary()
            row[label] = {k: s[k] for k in ("docked", "slip_throughs", "missed", "aborts",
                                            "terminal_err_down_median_m")}
        rows.append(row)
        if not args.json:
            w, o = row["with_model"], row["without_model"]
            print(f"{w['docked']:3d}/{args.trials} with, {o['docked']:3d}/{args.trials} without"
                  f"  (slips {w['slip_throughs']}, err {w['terminal_err_down_median_m']:.3f} m)"
                  f"  {name}", flush=True)
    if args.json:
        print(json.dumps(rows, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
