"""Issue 39's learnt size transfer: model kinds trained on the small pair alone (swap_ss 00-04),
judged on the heterogeneous day's flights (all of swap_sl), each follower apart.

    .venv/bin/python studies/size_transfer.py ss_train.npz sl_all.npz KIND [KIND ...]
        [--large-rotor-radius R [R ...]] [--footprint] [--smoke]

``ss_train.npz`` is ``aerodock ingest`` of swap_ss 00-04 and ``sl_all.npz`` of all swap_sl
flights with ``--vehicle cf51=small,cf101=large`` (docs/results/size-transfer.md gives the
commands). Prints, per kind and seed 0, 1, 2, the reduction of the interaction region's vertical
RMSE against the zero model (``evaluate``'s ``interaction.model.rmse_mps2.z`` against
``interaction.zero.rmse_mps2.z``) for the small follower under the large leader and the large
follower under the small one, then mean (sd, min-max). The large Crazyflie's rotor radius is
documented nowhere: the leader-aware kinds' wake scales read it from the flights' metadata
(the reader's assumption, 0.0325 m), and ``--large-rotor-radius`` judges them again with other
values (e.g. the wake fit's 0.0239 m) in its place; a kind that reads no wake scale is judged
once. ``--footprint`` judges each model again with a larger follower's rotor footprint
(:mod:`aerodock.learning.footprint`: the prediction averaged over the ring its wider diagonal
adds, from the vehicles' diagonals, nothing fitted). ``--smoke``: seed 0 and at most
:data:`SMOKE_EPOCHS` epochs (a test's size; its figures are no result).
"""

from __future__ import annotations

import argparse
import copy
from dataclasses import replace

from pairing_validation import (  # studies/ is on sys.path
    SEEDS,
    add_kinds_and_smoke,
    check_kinds,
    print_table,
    summary,
)

from aerodock.experiments.real_data import follower_vehicle
from aerodock.learning.datafiles import load_data_paths
from aerodock.learning.dataset import Dataset
from aerodock.learning.evaluate import evaluate
from aerodock.learning.kinds import get_kind
from aerodock.learning.train import train_model

SMOKE_EPOCHS = 5
"""``--smoke``'s epoch limit."""
LARGE_MASS_KG = 0.05
"""A vehicle heavier than this in the flights' metadata is the large Crazyflie (67 g; 32 g)."""
FOLLOWERS = {"small under large": "cf51", "large under small": "cf101"}


def with_large_rotor(ds: Dataset, radius_m: float) -> Dataset:
    """``ds`` with the large Crazyflie's rotor radius set to ``radius_m`` in every flight's
    metadata (as leader or follower): what the leader-aware kinds' wake scales read."""
    meta = copy.deepcopy(ds.meta)
    for flight in meta["flights"]:
        for role in ("leader", "follower"):
            if float(flight.get(f"{role}_mass_kg") or 0.0) > LARGE_MASS_KG:
                flight[f"{role}_rotor_radius_m"] = radius_m
    return replace(ds, meta=meta)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("ss_train", help="swap_ss 00-04 (aerodock ingest)")
    parser.add_argument("sl_all", help="every swap_sl flight (aerodock ingest --vehicle ...)")
    add_kinds_and_smoke(parser, SMOKE_EPOCHS)
    parser.add_argument("--footprint", action="store_true",
                        help="also judge each model over a larger follower's rotor footprint")
    parser.add_argument("--large-rotor-radius", type=float, nargs="+", default=[],
                        metavar="R", help="also judge with the large Crazyflie's rotor radius "
                                          "R m in the flights' metadata")
    args = parser.parse_args(argv)
    check_kinds(parser, args.kinds)
    if any(not r > 0 for r in args.large_rotor_radius):
        parser.error("--large-rotor-radius must be positive")
    fit = load_data_paths([args.ss_train])
    sl = load_data_paths([args.sl_all])
    seeds, options = ((0,), {"max_epochs": SMOKE_EPOCHS}) if args.smoke else (SEEDS, {})
    rows: dict[str, dict[str, list[float]]] = {}
    for kind in args.kinds:
        radii: list[float | None] = [None]  # the flights' own metadata first
        if get_kind(kind).n_wake_scales:
            radii += args.large_rotor_radius
        ways = [(radius, False) for radius in radii]
        if args.footprint:
            ways.append((None, True))
        for seed in seeds:
            predictor = train_model(kind, fit, seed=seed, **options).predictor()
            for radius, footprint in ways:
                judged = sl if radius is None else with_large_rotor(sl, radius)
                follower = follower_vehicle(judged)
                name = (f"{kind}, rotor footprint" if footprint else
                        kind if radius is None else f"{kind}, large rotor {radius:g} m")
                scores = rows.setdefault(name, {who: [] for who in FOLLOWERS})
                for who, vehicle in FOLLOWERS.items():
                    ev = evaluate(predictor, judged.subset(follower == vehicle),
                                  footprint=footprint)["interaction"]
                    scores[who].append(100 * (1 - ev["model"]["rmse_mps2"]["z"]
                                              / ev["zero"]["rmse_mps2"]["z"]))
                print(name, seed, {w: round(v[-1], 1) for w, v in scores.items()}, flush=True)
    for name, scores in rows.items():
        for who, values in scores.items():
            print(f"SIZE {name} {who}: {summary(values)}", flush=True)
    print_table(f"model, trained on the small pair, seeds {', '.join(map(str, seeds))}", rows)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
