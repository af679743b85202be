"""The sim-to-real check: a downwash model trained only on simulated flights of the Crazyflie
worlds, judged on the real Neural-Swarm flights beside the zero model and a model trained on real
flights (aerodock/experiments/sim_to_real.py has what is flown, trained and judged).

    .venv/bin/python studies/sim_to_real.py [--quick] [--seed 0 [1 2]] [--model so2]
        [--pair small_under_small|small_under_large|large_under_small]
        [--data $AERODOCK_DATA_DIR/neural-swarm]
        [--swaps 30] [--out sim_to_real.json] [--json] [--smoke]

The worlds are examples/crazyflie.toml (small under small),
examples/crazyflie_small_under_large.toml (small under large) and
examples/crazyflie_large_under_small.toml (large under small). The simulated flights are the
curriculum's wake-excitation flights and the Neural-Swarm swap task's (aerodock/collect/swaps.py).
``--smoke``: small under small only (unless ``--pair`` names one), one flight in three depth
bands and one swap, 8 epochs.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from _smoke import add_smoke_option  # studies/, on sys.path

from aerodock.config import load_config
from aerodock.experiments.sim_to_real import PAIRS, mean_over_seeds, sim_to_real_study
from aerodock.fileio import write_json
from aerodock.ingest.data_dir import find_data_dir

ROOT = Path(__file__).resolve().parents[1]
# The data location (aerodock.ingest.data_dir): AERODOCK_DATA_DIR, else ../shared/data.
DATA_DIR = find_data_dir().path or ROOT.parent / "shared" / "data"
WORLDS = {"small_under_small": ROOT / "examples" / "crazyflie.toml",
          "small_under_large": ROOT / "examples" / "crazyflie_small_under_large.toml",
          "large_under_small": ROOT / "examples" / "crazyflie_large_under_small.toml"}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path,
                        default=DATA_DIR / "neural-swarm")
    parser.add_argument("--pair", choices=sorted(PAIRS), action="append",
                        help="a pairing to judge (repeatable; default: all three)")
    parser.add_argument("--model", default="so2", choices=("so2", "so2-ext", "mlp"))
    parser.add_argument("--quick", action="store_true", help="2 flights per band, 40 epochs")
    parser.add_argument("--seed", type=int, nargs="+", default=[0],
                        help="seed(s) of the flights and weights; several: each in turn, then "
                             "their mean (the figures move by a few points with the seed)")
    parser.add_argument("--swaps", type=int, default=None,
                        help="swap-task flights among the simulated ones (default: the study's "
                             "30; 0: the curriculum's flights alone)")
    parser.add_argument("--out", type=Path, help="write the results as JSON here")
    parser.add_argument("--json", action="store_true", help="print the results as JSON")
    add_smoke_option(parser)
    args = parser.parse_args()
    if args.swaps is not None and args.swaps < 0:
        parser.error(f"--swaps must be 0 or more, got {args.swaps}")
    if args.smoke and not args.pair:
        args.pair = ["small_under_small"]
    if not args.data.is_dir():
        print(f"error: {args.data}: no such folder (the Neural-Swarm flights)", file=sys.stderr)
        return 2
    worlds = {key: load_config(WORLDS[key]) for key in (args.pair or sorted(PAIRS))}
    results = [sim_to_real_study(worlds, args.data, kind=args.model, quick=args.quick,
                                 seed=seed, smoke=args.smoke, swaps=args.swaps,
                                 progress=None if args.json else lambda m: print(m, flush=True))
               for seed in args.seed]
    several = len(results) > 1
    record = ({"seeds": args.seed, "runs": results, "mean": mean_over_seeds(results)}
              if several else results[0])
    if args.out is not None:
        write_json(args.out, record, final_newline=True)
    if args.json:
        print(json.dumps(record, indent=2))
        return 0
    for seed, result in zip(args.seed, results, strict=True):
        for key, r in result["pairs"].items():
            rm, red = r["rmse_vertical_mps2"], r["reduction_vs_zero"]
            print(f"{f'seed {seed}: ' if several else ''}{r['pair']}: interaction vertical RMSE "
                  f"zero {rm['zero']:.3f}, simulation-trained {rm['sim']:.3f} "
                  f"({red['sim']:.1%}), real-trained {rm['real']:.3f} ({red['real']:.1%}), the "
                  f"world's own mean wake {rm['field']:.3f} ({red['field']:.1%}) m/s^2, "
                  f"{r['interaction_samples']} samples; target >= {r['target_reduction']:.0%}: "
                  f"{'met' if r['met'] else 'not met'} [{key}]")
    if several:
        for key, m in record["mean"].items():
            red = m["reduction_vs_zero"]
            print(f"mean of {m['seeds']} seeds, {PAIRS[key].name}: simulation-trained "
                  f"{red['sim']:.1%}, real-trained {red['real']:.1%}, the world's own mean wake "
                  f"{red['field']:.1%}; within 5 points of the real-trained model and above the "
                  f"mean wake: {'yes' if m['close_to_real'] else 'no'} [{key}]")
    return 0


if __name__ == "__main__":
    sys.exit(main())
