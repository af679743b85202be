"""Train a downwash model on flight logs from Python, and judge it on flights it never saw.

Two sources of FlightLogs, the one record format of simulated and real flights:

- ``real``: the Neural-Swarm flights in the data location (``--data-dir``, else
  ``$AERODOCK_DATA_DIR``, else this repository's ``../shared/data``; docs/real-logs.md says where
  to get them): trained on swap_ss flights 00-04, judged on 05-06, as ``aerodock reproduce``'s
  real-data study does;
- ``simulated``: wake-excitation flights of the curriculum (the follower 0.3-0.6 m under the
  leader), flown here: all but the last trained on, the last judged.

``auto`` (the default) takes the real flights when the data location holds them. The model is
written to ``--out`` (a model directory: ``aerodock evaluate``, ``export``, ``dock --model`` and
``Predictor.load`` read it).

    python examples/train_on_logs.py --out out/model                  # ~1-2 min
    python examples/train_on_logs.py --source simulated --out out/model
    python examples/train_on_logs.py --smoke --out out/model --json    # seconds (the tests)

Needs PyTorch (``aerodock[learn]``) to train; the model it writes runs on NumPy alone.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from aerodock.flightlog import FlightLog
from aerodock.ingest.data_dir import find_data_dir, has_swap_flights

SIZES = {"smoke": {"flights": 3, "epochs": 5}, "full": {"flights": 12, "epochs": 100}}
"""Simulated flights flown (the last one judged) and the epoch limit, by run size."""
DEPTH_BAND_M = (0.3, 0.6)
"""The simulated flights' depth band below the leader, m (the curriculum's deep stages)."""


def simulated_logs(n_flights: int, seed: int = 0) -> tuple[list[FlightLog], list[FlightLog]]:
    """(training flights, held-out flight): ``n_flights`` wake-excitation flights flown at
    once in the default world; the last is held out."""
    from aerodock.collect.curriculum import excitation_flights
    from aerodock.config import load_config

    logs = excitation_flights(load_config(), n_flights, *DEPTH_BAND_M, seed=seed, name="sim")
    return logs[:-1], logs[-1:]


def real_logs(neural_swarm: Path) -> tuple[list[FlightLog], list[FlightLog]]:
    """(training flights, held-out flights) of ``neural_swarm/swap_ss``: 00-04 and 05-06, both
    vehicles of each as the follower."""
    from aerodock.experiments.real_data import real_split

    train_logs, test_logs, _, _ = real_split(neural_swarm / "swap_ss")
    return train_logs, test_logs


def train_and_judge(train_logs: list[FlightLog], test_logs: list[FlightLog], out: Path,
                    kind: str = "so2", max_epochs: int = 100, seed: int = 0) -> dict[str, Any]:
    """Labels from the logs, a model trained and written to ``out``, its held-out error beside
    the zero model's (in the interaction region: the follower below the leader)."""
    from aerodock.learning.dataset import build_dataset
    from aerodock.learning.evaluate import evaluate
    from aerodock.learning.runtime import Predictor
    from aerodock.learning.train import train_model

    train_ds, test_ds = build_dataset(train_logs), build_dataset(test_logs)
    trained = train_model(kind, train_ds, max_epochs=max_epochs, seed=seed)
    path = trained.save(out)
    judged = evaluate(Predictor.load(path), test_ds)  # the model as every reader loads it
    region = judged["interaction"]
    return {"model_dir": str(path), "kind": kind, "train_flights": len(train_logs),
            "test_flights": len(test_logs), "train_minutes": round(train_ds.minutes, 3),
            "epochs": trained.info["epochs"], "val_rmse_mps2": trained.info["val_rmse_mps2"],
            "heldout_interaction_samples": region["n"],
            "heldout_rmse_down_mps2": region["model"]["rmse_mps2"]["z"],
            "zero_model_rmse_down_mps2": region["zero"]["rmse_mps2"]["z"]}


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Parse the options, read or fly the logs, train, judge, print (and return) the result."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--source", choices=("auto", "real", "simulated"), default="auto")
    parser.add_argument("--data-dir", type=Path, default=None,
                        help="the data location holding neural-swarm/ (default: "
                             "$AERODOCK_DATA_DIR, else ../shared/data)")
    parser.add_argument("--out", type=Path, default=Path("out/example_model"),
                        help="model directory to write")
    parser.add_argument("--kind", default="so2", help="so2 (the paper's), so2-ext or mlp")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--smoke", action="store_true", help="seconds (the tests)")
    parser.add_argument("--json", action="store_true", help="print the result as JSON")
    args = parser.parse_args(argv)
    size = SIZES["smoke" if args.smoke else "full"]
    located = find_data_dir(args.data_dir)
    if located.problem():
        raise ValueError(located.problem())
    real = located.neural_swarm()
    source = args.source
    if source == "auto":
        source = "real" if has_swap_flights(real) else "simulated"
    if source == "real":
        if not has_swap_flights(real):
            raise ValueError(f"{real or 'no data location'}: no neural-swarm/swap_ss flights "
                             "(give --data-dir or set AERODOCK_DATA_DIR; docs/real-logs.md)")
        train_logs, test_logs = real_logs(real)
    else:
        train_logs, test_logs = simulated_logs(size["flights"], args.seed)
    result = {"source": source, **train_and_judge(train_logs, test_logs, args.out, args.kind,
                                                  size["epochs"], args.seed)}
    if args.json:
        print(json.dumps(result))
    else:
        print(f"{result['kind']} on {result['train_flights']} {source} flights "
              f"({result['train_minutes']:.1f} min), {result['epochs']} epochs; held out "
              f"({result['test_flights']} flights, follower below the leader): vertical RMSE "
              f"{result['heldout_rmse_down_mps2']:.3f} m/s² against the zero model's "
              f"{result['zero_model_rmse_down_mps2']:.3f}")
        print(f"wrote {result['model_dir']}")
    return result


if __name__ == "__main__":
    try:
        main(sys.argv[1:])
    except ImportError:
        print("error: training needs PyTorch: pip install 'aerodock[learn]'", file=sys.stderr)
        sys.exit(2)
    except (ValueError, OSError) as err:  # no flights, bad data, an unwritable --out: one line
        print(f"error: {' '.join(str(err).split())}", file=sys.stderr)
        sys.exit(2)
