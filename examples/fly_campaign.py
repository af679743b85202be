"""Fly a docking campaign from Python: the four names of aerodock's API in a dozen lines.

``load_config`` gives the defaults (or a TOML file's overrides), ``controller_config`` sets the
follower's controller (``paper``, ``tuned`` or ``ours``), ``MissionSpec`` says what to fly
(trials, cable length d_p, leader speed, compensation, seed) and ``run_campaign`` flies every
trial at once, batch-first. ``Predictor.load`` reads a trained model for ``--compensation
model``. The same campaign as ``aerodock dock`` with the same options (tested).

    python examples/fly_campaign.py                        # 50 trials, ours, observer: seconds
    python examples/fly_campaign.py --controller paper --compensation model --model out/model
    python examples/fly_campaign.py --smoke --json         # 4 trials: seconds (the tests)
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from aerodock.config import load_config
from aerodock.control.compensation import Compensation
from aerodock.control.profiles import PROFILES, controller_config
from aerodock.learning.runtime import Predictor
from aerodock.mission import MissionSpec, run_campaign


def fly(trials: int = 50, offset_m: float = 0.36, controller: str = "ours",
        compensation: str = "observer", model_dir: Path | None = None,
        leader_speed_mps: float = 0.0, seed: int = 0,
        config: Path | None = None) -> dict[str, Any]:
    """One campaign; returns its summary (docked with a Wilson 95 % interval, errors, aborts:
    :meth:`aerodock.mission.CampaignResult.summary`)."""
    cfg = controller_config(load_config(config), controller)
    spec = MissionSpec(trials=trials, offset_m=offset_m, leader_speed_mps=leader_speed_mps,
                       compensation=Compensation(compensation), seed=seed)
    predictor = Predictor.load(model_dir) if model_dir is not None else None
    result = run_campaign(cfg, spec, predictor)  # every trial at once, one NumPy call a step
    return result.summary()


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Parse the options, fly, print the summary (and return it)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=None, help="trials (default 50)")
    parser.add_argument("--offset", type=float, default=0.36, help="cable length d_p, m")
    parser.add_argument("--controller", choices=PROFILES, default="ours")
    parser.add_argument("--compensation", choices=[c.value for c in Compensation],
                        default="observer")
    parser.add_argument("--model", type=Path, default=None, help="trained model DIR (model)")
    parser.add_argument("--leader-speed", type=float, default=0.0, help="m/s, north")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--config", type=Path, default=None, help="TOML overrides")
    parser.add_argument("--smoke", action="store_true", help="4 trials: seconds (the tests)")
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")
    args = parser.parse_args(argv)
    trials = args.trials or (4 if args.smoke else 50)
    summary = fly(trials, args.offset, args.controller, args.compensation, args.model,
                  args.leader_speed, args.seed, args.config)
    if args.json:
        print(json.dumps(summary))
    else:
        lo, hi = summary["success_wilson95"]
        print(f"{args.controller}, {args.compensation}, d_p {args.offset:g} m: docked "
              f"{summary['docked']}/{trials} (Wilson 95 % {lo:.0%}-{hi:.0%}), aborts "
              f"{summary['aborts']}, terminal error down (median) "
              f"{summary['terminal_err_down_median_m']:.3f} m")
    return summary


if __name__ == "__main__":
    try:
        main(sys.argv[1:])
    except (ValueError, OSError) as err:  # bad options, a missing or damaged model: one line
        print(f"error: {' '.join(str(err).split())}", file=sys.stderr)
        sys.exit(2)
