"""Training choices judged on a validation split of the training flights only (issue 24's
large-under-small target): train on swap_ss 00-04 + swap_sl 00-04, judge on swap_sl 05-07, each
follower apart; the held-out swap_sl 08-11 are not read.

    .venv/bin/python studies/pairing_validation.py ss_train.npz sl_train.npz [CANDIDATE ...]
        [--smoke]    # the first candidate, two seeds, a few epochs

``ss_train.npz`` and ``sl_train.npz`` are ``aerodock ingest`` of swap_ss 00-04 and swap_sl 00-07
(docs/results/label-floor.md gives the commands). Prints, per candidate and seed 0, 1, 2, the
reduction of the interaction region's vertical RMSE against the zero model on swap_sl 05-07 per
follower (``cf51`` small, ``cf101`` large), then mean (sd, min-max). Candidates: see ``CANDIDATES``.
"""

from __future__ import annotations

import argparse

import numpy as np
from _smoke import SMOKE_EPOCHS, add_smoke_option

from aerodock.experiments.real_data import follower_vehicle
from aerodock.learning.datafiles import load_data_paths
from aerodock.learning.dataset import Dataset, concat_datasets
from aerodock.learning.evaluate import evaluate
from aerodock.learning.train import train_model

# name: (kind, train on swap_ss too, train_model options)
CANDIDATES: dict[str, tuple[str, bool, dict]] = {
    "so2": ("so2", True, {}),
    "so2-leader": ("so2-leader", True, {}),
    "so2-pair": ("so2-pair", True, {}),
    "deepsets": ("deepsets", True, {}),
    "so2 patience40": ("so2", True, {"patience": 40}),
    "so2 hidden128": ("so2", True, {"hidden": (128, 128)}),
    "so2 hidden32": ("so2", True, {"hidden": (32, 32)}),
    # a diagnostic, not a choice: without the small pair, is the large follower learnt better?
    "so2 sl-only": ("so2", False, {}),
    "so2-leader sl-only": ("so2-leader", False, {}),
}
SEEDS = (0, 1, 2)
FIT_LAST, VALIDATION = 4, (5, 6, 7)


def score_seeds(tag: str, name: str, kind: str, fit: Dataset, judged: dict[str, Dataset],
                options: dict | None = None, seeds: tuple[int, ...] = SEEDS
                ) -> dict[str, list[float]]:
    """Train ``kind`` on ``fit`` for each of ``seeds`` and print, per data set of ``judged``,
    the interaction region's vertical RMSE reduction against the zero model (%), per seed and
    then as ``TAG NAME WHO: mean % (sd, min-max)`` (the sd with two seeds or more); returns the
    reductions."""
    scores: dict[str, list[float]] = {who: [] for who in judged}
    for seed in seeds:
        predictor = train_model(kind, fit, seed=seed, **(options or {})).predictor()
        for who, ds in judged.items():
            ev = evaluate(predictor, ds)["interaction"]
            scores[who].append(100 * (1 - ev["model"]["rmse_mps2"]["z"]
                                      / ev["zero"]["rmse_mps2"]["z"]))
        print(name, seed, {who: round(v[-1], 1) for who, v in scores.items()}, flush=True)
    for who, v in scores.items():
        print(f"{tag} {name} {who}: {summary(v)}", flush=True)
    return scores


def add_kinds_and_smoke(parser: argparse.ArgumentParser, smoke_epochs: int) -> None:
    """The model kinds to train (positional, checked by :func:`check_kinds`) and ``--smoke``
    (seed 0, at most ``smoke_epochs`` epochs)."""
    from aerodock.learning.features import KINDS

    parser.add_argument("kinds", nargs="+", help=f"model kinds ({', '.join(KINDS)})")
    parser.add_argument("--smoke", action="store_true",
                        help=f"seed 0, at most {smoke_epochs} epochs (a test's size)")


def check_kinds(parser: argparse.ArgumentParser, kinds: list[str]) -> None:
    """Refuse an unknown model kind (the parser's one-line error)."""
    from aerodock.learning.features import KINDS

    bad = [k for k in kinds if k not in KINDS]
    if bad:
        parser.error(f"unknown model kind {bad[0]!r}")


def print_table(title: str, rows: dict[str, dict[str, list[float]]]) -> None:
    """The markdown table of ``rows`` (a row's name -> per judged set, its reductions in %):
    ``title`` heads the first column, each judged set one more."""
    judged = list(next(iter(rows.values()))) if rows else []
    print(f"\n| {title} | {' | '.join(judged)} |")
    print("|---" * (len(judged) + 1) + "|")
    for name, scores in rows.items():
        print(f"| `{name}` | {' | '.join(summary(v) for v in scores.values())} |")


def summary(values: list[float]) -> str:
    """``mean % (sd, min-max)`` of reductions in %, the sd with two values or more."""
    arr = np.array(values)
    sd = f"{arr.std(ddof=1):.1f}, " if arr.size > 1 else ""
    return f"{arr.mean():.1f} % ({sd}{arr.min():.1f}-{arr.max():.1f})"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("ss_train", help="swap_ss 00-04 (aerodock ingest)")
    parser.add_argument("sl_train", help="swap_sl 00-07 (aerodock ingest --vehicle ...)")
    parser.add_argument("candidates", nargs="*", help=f"some of {', '.join(CANDIDATES)}")
    add_smoke_option(parser)
    args = parser.parse_args()
    unknown = [c for c in args.candidates if c not in CANDIDATES]
    if unknown:
        parser.error(f"unknown candidate {unknown[0]!r}")
    ss, sl = load_data_paths([args.ss_train]), load_data_paths([args.sl_train])
    number = np.array([int(n.rsplit("_", 2)[-2]) for n in sl.flight_names])[sl.flight_id]
    follower = follower_vehicle(sl)
    if number.max() > max(VALIDATION):
        parser.error("sl_train holds flights after 07: the held-out flights must not be read")
    sl_fit = sl.subset(number <= FIT_LAST)
    validation = {who: sl.subset(np.isin(number, VALIDATION) & (follower == who))
                  for who in ("cf51", "cf101")}
    names = args.candidates or list(CANDIDATES)
    for name in names[:1] if args.smoke else names:
        kind, with_ss, options = CANDIDATES[name]
        fit = concat_datasets([ss, sl_fit]) if with_ss else sl_fit
        if args.smoke:
            score_seeds("VAL", name, kind, fit, validation,
                        {**options, "max_epochs": SMOKE_EPOCHS}, seeds=SEEDS[:2])
        else:
            score_seeds("VAL", name, kind, fit, validation, options)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
