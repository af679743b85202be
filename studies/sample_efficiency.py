"""Sample efficiency re-measured: so2, so2-ext and the MLP against minutes of training data.

    .venv/bin/python studies/sample_efficiency.py --part sim --size full --out runs/se-sim
    .venv/bin/python studies/sample_efficiency.py --part real --out runs/se-real \
        [--real-folder $AERODOCK_DATA_DIR/neural-swarm/swap_ss]
    .venv/bin/python studies/sample_efficiency.py --part real|sim --smoke --out DIR   # seconds

``sim``: step 1 of ``aerodock reproduce`` (the curriculum's flights and models, held-out
excitation flights, the sample-efficiency pool: :func:`aerodock.experiments.reproduce.
learning_data`) at the reproduction's ``--size`` (``quick`` or ``full``), then
:func:`aerodock.experiments.sample_efficiency.sample_efficiency` as the reproduction calls it;
``--minutes`` / ``--seeds`` replace the size's (an intermediate size, named in the output).
``real``: the sample-efficiency part of the real-data study (Neural-Swarm swap_ss, train on
flights 00-04, judge on 05-06, metric ``interaction``, :func:`aerodock.experiments.real_data.
real_split`) at its full minutes and seeds unless replaced. ``--smoke``: the smallest run that
crosses every step (``reproduce --smoke``'s size for ``sim``; half a minute of data, one seed
and a few epochs a training for both).

Prints, per kind and minutes, the mean (sd over seeds) held-out RMSE, m/s², over all samples and
over the interaction region, and the zero model's; writes ``OUT/sample_efficiency_PART.json``
(and the library's own ``sample_efficiency.json`` and figure in ``OUT/figures-PART``).
"""

from __future__ import annotations

import argparse
import dataclasses
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

from _smoke import SMOKE_EPOCHS, add_smoke_option  # studies/, on sys.path

from aerodock.config import load_config
from aerodock.experiments import real_data
from aerodock.experiments.reproduce import FULL, QUICK, SMOKE, learning_data
from aerodock.experiments.sample_efficiency import sample_efficiency
from aerodock.fileio import json_ready, write_json
from aerodock.ingest.data_dir import find_data_dir
from aerodock.learning.dataset import build_dataset

ROOT = Path(__file__).resolve().parents[1]
# The data location (aerodock.ingest.data_dir): AERODOCK_DATA_DIR, else ../shared/data.
DATA_DIR = find_data_dir().path or ROOT.parent / "shared" / "data"
KINDS = ("so2", "so2-ext", "mlp")


def _say(msg: str) -> None:
    print(f"sample-efficiency: {msg}", file=sys.stderr, flush=True)


def _progress(desc: str, done: int, total: int) -> None:
    _say(f"{done}/{total} {desc}")


def _table(se: dict[str, Any]) -> str:
    """Mean (sd) RMSE per kind and minutes, both regions, and the zero model's."""
    lines = [f"{'kind':<8} {'minutes':>7} {'rmse_all':>16} {'rmse_interaction':>18}"]
    for kind, entry in se["models"].items():
        for i, m in enumerate(se["minutes"]):
            a, sa = entry["rmse_all_mean"][i], entry["rmse_all_sd"][i]
            b, sb = entry["rmse_interaction_mean"][i], entry["rmse_interaction_sd"][i]
            lines.append(f"{kind:<8} {m:>7g} {a:>8.3f} ({sa:.3f}) {b:>10.3f} ({sb:.3f})")
    lines.append(f"{'zero':<8} {'':>7} {se['zero']['all']:>8.3f} {'':>7} "
                 f"{se['zero']['interaction']:>10.3f}")
    floor = se.get("error_floor") or {}
    if floor.get("all") is not None:
        lines.append(f"{'floor':<8} {'':>7} {floor['all']:>8.3f} {'':>7} "
                     f"{floor['interaction']:>10.3f}")
    return "\n".join(lines)


def _commit() -> str:
    out = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True)
    dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=ROOT,
                           capture_output=True, text=True).stdout.strip()
    return out.stdout.strip() + (" (with uncommitted changes)" if dirty else "")


def main(argv: list[str] | None = None) -> int:
    """Measure one part and print its table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--part", choices=("sim", "real"), required=True)
    parser.add_argument("--size", choices=("quick", "full"), default="full",
                        help="sim: the reproduction's run size")
    parser.add_argument("--minutes", type=float, nargs="+", default=None,
                        help="minutes of training data (replace the size's)")
    parser.add_argument("--seeds", type=int, nargs="+", default=None,
                        help="seeds (replace the size's)")
    parser.add_argument("--seed", type=int, default=0, help="sim: the reproduction's --seed")
    parser.add_argument("--real-folder", type=Path,
                        default=DATA_DIR / "neural-swarm" / "swap_ss")
    parser.add_argument("--out", type=Path, required=True, help="output folder")
    add_smoke_option(parser)
    args = parser.parse_args(argv)
    train_kwargs = {"max_epochs": SMOKE_EPOCHS} if args.smoke else None
    if args.smoke:
        args.size = "smoke"
        args.minutes, args.seeds = args.minutes or [0.5], args.seeds or [0]
    if args.minutes is not None and min(args.minutes) <= 0:
        parser.error("--minutes must be > 0")
    if args.part == "real" and not args.real_folder.is_dir():
        parser.error(f"no folder {args.real_folder}")
    args.out.mkdir(parents=True, exist_ok=True)
    fig_dir = args.out / f"figures-{args.part}"
    started = time.perf_counter()
    record: dict[str, Any] = {"part": args.part, "commit": _commit(), "kinds": list(KINDS)}
    if args.part == "sim":
        size = {"full": FULL, "quick": QUICK, "smoke": SMOKE}[args.size]
        if args.minutes is not None or args.seeds is not None:
            size = dataclasses.replace(
                size, se_minutes=tuple(args.minutes or size.se_minutes),
                se_seeds=tuple(size.se_seeds if args.seeds is None else args.seeds))
        record["size"] = {"base": args.size, "intermediate": size not in (FULL, QUICK, SMOKE),
                          "se_minutes": size.se_minutes, "se_seeds": size.se_seeds,
                          "se_pool_flights": size.se_pool_flights,
                          "test_flights_per_stage": size.test_flights_per_stage,
                          "se_max_epochs": size.se_max_epochs}
        _say("curriculum, held-out flights and the pool (reproduce step 1)")
        learning = learning_data(load_config(), size, args.out / "data", args.seed, say=_say)
        record["curriculum_s"] = time.perf_counter() - started
        t0 = time.perf_counter()
        se = sample_efficiency(
            build_dataset(learning.train_logs), learning.test_ds, kinds=KINDS,
            minutes=size.se_minutes, seeds=size.se_seeds, out_dir=fig_dir,
            train_kwargs={**({"max_epochs": size.se_max_epochs} if size.se_max_epochs else {}),
                          **(train_kwargs or {})} or None,
            progress=_progress)
    else:
        minutes = tuple(args.minutes or real_data.SE_MINUTES["full"])
        seeds = tuple(real_data.SE_SEEDS["full"] if args.seeds is None else args.seeds)
        train_logs, test_logs, train_ds, test_ds = real_split_or_fail(args.real_folder)
        record.update(folder=str(args.real_folder), train_flights=[lg.name for lg in train_logs],
                      test_flights=[lg.name for lg in test_logs])
        t0 = time.perf_counter()
        se = sample_efficiency(train_ds, test_ds, kinds=KINDS, minutes=minutes, seeds=seeds,
                               out_dir=fig_dir, metric="interaction", train_kwargs=train_kwargs,
                               progress=_progress)
    record["sample_efficiency_s"] = time.perf_counter() - t0
    record["total_s"] = time.perf_counter() - started
    record["sample_efficiency"] = se
    path = write_json(args.out / f"sample_efficiency_{args.part}.json", json_ready(record),
                      final_newline=True)
    print(_table(se))
    print(f"minutes available {se['minutes_available']}, skipped {se['skipped_minutes']}, "
          f"wall {record['total_s']:.0f} s; {path}")
    return 0


def real_split_or_fail(folder: Path) -> Any:
    """:func:`real_data.real_split`, with no usable flight a one-line error."""
    split = real_data.real_split(folder)
    if not split[0] or not split[1]:
        raise SystemExit(f"error: {folder} holds no flights 00-04 and 05-06")
    return split


if __name__ == "__main__":
    raise SystemExit(main())
