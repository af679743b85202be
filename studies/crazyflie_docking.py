"""Hover docking in a Crazyflie world: the paper's controller and ours, each without and with a
model, as `aerodock dock` flies them (the same campaigns, one table).

    .venv/bin/python studies/crazyflie_docking.py --models C [--collect]
        [--config examples/crazyflie.toml] [--force-at-centre] [--offset 0.12] [--trials 40]
        [--seed 0] [--json] [--smoke]

The models are a curriculum's (``aerodock collect --config <the same world> --out C``, or this
script's ``--collect``, which flies it into C first, in the world the campaigns fly):
C/models/paper (the paper's curriculum) for the paper's controller, C/models/final (the deep
curriculum) for ours, as in the README's headline table. ``--force-at-centre`` flies the world
with the jet's force at the follower's centre of mass (``aerodock.downwash.at_centre``: no wake
torque), the other side of a bracket round the jet's torque (docs/crazyflie.md). ``--smoke``
flies ours with the model only, two trials, the mission's waits cut (and ``--collect`` the
smallest curriculum, ``reproduce --smoke``'s).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from _smoke import (  # studies/, on sys.path
    SMOKE_CURRICULUM,
    SMOKE_EPOCHS,
    SMOKE_TRIALS,
    add_smoke_option,
    smoke_config,
)

from aerodock.config import load_config
from aerodock.control.compensation import Compensation
from aerodock.control.profiles import controller_config
from aerodock.learning.runtime import Predictor
from aerodock.mission import MissionSpec, run_campaign
from aerodock.mission.checks import check_mission

ROOT = Path(__file__).resolve().parents[1]
KEYS = ("docked", "trials", "success_wilson95", "slip_throughs", "missed", "aborts",
        "abort_reasons", "terminal_err_down_median_m", "terminal_err_3d_median_m",
        "terminal_tilt_rms_deg_median", "rotor_strikes")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", type=Path, default=ROOT / "examples" / "crazyflie.toml")
    parser.add_argument("--models", type=Path, required=True, help="a curriculum's folder")
    parser.add_argument("--collect", action="store_true", help="fly the curriculum into it")
    parser.add_argument("--offset", type=float, default=None, help="d_p, m (the config's)")
    parser.add_argument("--trials", type=int, default=40)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--force-at-centre", action="store_true")
    parser.add_argument("--json", action="store_true")
    add_smoke_option(parser)
    args = parser.parse_args()
    base = load_config(args.config)
    if args.smoke:
        base = smoke_config(base).with_overrides({"curriculum": SMOKE_CURRICULUM})
        args.trials = SMOKE_TRIALS
    if args.force_at_centre:
        base = base.with_overrides(  # a new field takes only the params given with it
            {"downwash": {"field": "aerodock.downwash.at_centre:RoundJetAtCentre",
                          "params": dict(base.data["downwash"]["params"])}},
            source=f"{args.config} + force at the centre of mass")
    curriculum = None
    if args.collect:
        from aerodock.collect.curriculum import run_curriculum

        curriculum = run_curriculum(base, args.models, seed=args.seed, progress=None if args.json
                                    else lambda m: print(m, flush=True),
                                    train_kwargs={"max_epochs": SMOKE_EPOCHS} if args.smoke
                                    else None)
    rows = []
    runs = (("paper", args.models / "models" / "paper"), ("ours", args.models / "models" / "final"))
    for controller, model in runs[1:] if args.smoke else runs:
        predictor = Predictor.load(model)
        comps = (Compensation.OBSERVER, Compensation.MODEL)
        for comp in comps[1:] if args.smoke else comps:
            spec = MissionSpec(trials=args.trials, offset_m=args.offset, compensation=comp,
                               seed=args.seed)
            cfg = check_mission(controller_config(base, controller), spec)
            s = run_campaign(cfg, spec, predictor if comp == Compensation.MODEL else None
                             ).summary()
            row = {"controller": controller, "compensation": comp.value,
                   "model": str(model) if comp == Compensation.MODEL else None,
                   "offset_m": cfg.platform.cable_length_m, **{k: s[k] for k in KEYS}}
            rows.append(row)
            if not args.json:
                lo, hi = row["success_wilson95"]
                print(f"{controller:5s} {comp.value:8s} {row['docked']:3d}/{row['trials']} "
                      f"({lo:.0%}-{hi:.0%}) slips {row['slip_throughs']} missed "
                      f"{row['missed']} aborts {row['aborts']} {row['abort_reasons']} "
                      f"err down {row['terminal_err_down_median_m']:.4f} m, 3D "
                      f"{row['terminal_err_3d_median_m']:.4f} m, tilt "
                      f"{row['terminal_tilt_rms_deg_median']:.1f} deg", flush=True)
    if args.json:
        print(json.dumps({"config": base.source, "field": base.downwash.field,
                          "curriculum": curriculum, "rows": rows}, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
