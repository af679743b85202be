"""The leader moving rapidly (the paper's future work): our controller docking under a leader at
up to 1 m/s, straight or turning, with the bias observer alone, the learnt model and the
oracle (the simulator's true mean field, wake skew included), and how far the learnt model's
mean vertical force is from the field's where the follower docks.

    .venv/bin/python studies/fast_leader.py --model DIR [--trials 100] [--seed 0] [--json]
        [--smoke]    # the first case with the model only, two trials, the mission's waits cut

The learnt model's features include both vehicles' velocities, so a skewed wake is something it
can represent; whether it does at speeds it never saw in the curriculum (which flies the leader
at up to 0.5 m/s) is what the model-against-oracle gap shows.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from _smoke import SMOKE_TRIALS, add_smoke_option, smoke_config  # studies/, on sys.path

from aerodock.config import load_config
from aerodock.control.compensation import Compensation
from aerodock.control.profiles import controller_config
from aerodock.learning.runtime import Predictor
from aerodock.mission import MissionSpec, run_campaign

CASES = ((0.5, 0.0), (1.0, 0.0), (1.0, 0.2))  # leader speed m/s, turn rate rad/s
COMPENSATIONS = (Compensation.OBSERVER, Compensation.MODEL, Compensation.ORACLE)
KEYS = ("docked", "trials", "success_wilson95", "slip_throughs", "missed", "aborts",
        "terminal_err_down_median_m", "terminal_tilt_rms_deg_median", "rotor_strikes")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", type=Path, required=True)
    parser.add_argument("--controller", default="ours", choices=("paper", "tuned", "ours"))
    parser.add_argument("--trials", type=int, default=100)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", action="store_true")
    add_smoke_option(parser)
    args = parser.parse_args()
    cfg = controller_config(load_config(), args.controller)
    cases = CASES[:1] if args.smoke else CASES
    if args.smoke:
        cfg, args.trials = smoke_config(cfg), SMOKE_TRIALS
    predictor = Predictor.load(args.model)
    rows = []
    for speed, turn in cases:
        for comp in (Compensation.MODEL,) if args.smoke else COMPENSATIONS:
            res = run_campaign(cfg, MissionSpec(
                trials=args.trials, offset_m=0.36, leader_speed_mps=speed,
                leader_turn_rate_radps=turn, compensation=comp, seed=args.seed),
                predictor if comp == Compensation.MODEL else None)
            s = res.summary()
            row = {"leader_speed_mps": speed, "turn_rate_radps": turn,
                   "compensation": comp.value, **{k: s[k] for k in KEYS}}
            rows.append(row)
            if not args.json:
                lo, hi = row["success_wilson95"]
                print(f"{speed:.1f} m/s turn {turn:.1f} rad/s {comp.value:8s} "
                      f"{row['docked']:3d}/{row['trials']} ({lo:.0%}-{hi:.0%}) "
                      f"slips {row['slip_throughs']:2d} aborts {row['aborts']:2d} "
                      f"err {row['terminal_err_down_median_m']:.4f} m "
                      f"tilt {row['terminal_tilt_rms_deg_median']:.1f} deg", flush=True)
    if args.json:
        print(json.dumps(rows, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
