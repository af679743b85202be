"""Issue 24's real-flight targets, one model kind: trained on swap_ss 00-04 + swap_sl 00-07,
judged on the held-out swap_sl 08-11 (each follower apart) and swap_ss 05-06.

    .venv/bin/python studies/pairing_heldout.py ss_train.npz sl_train.npz ss_test.npz \\
        sl_test.npz KIND [KIND ...] [--smoke]

The data files are ``aerodock ingest`` of swap_ss 00-04, swap_sl 00-07, swap_ss 05-06 and
swap_sl 08-11 (docs/results/so2-pair.md gives the commands). Prints, per kind and seed 0, 1, 2, the
reduction of the interaction region's vertical RMSE against the zero model (``evaluate``'s
``interaction.model.rmse_mps2.z`` against ``interaction.zero.rmse_mps2.z``, the leader-aware
kinds given the data's wake scales), then mean (sd, min-max): the same figures as
``aerodock train`` then ``aerodock evaluate`` on the flights of one follower. Last, the table
(docs/results/deep-sets.md): one row per kind. ``--smoke``: seed 0 and at most
:data:`SMOKE_EPOCHS` epochs (a test's size; its figures are no result).
"""

from __future__ import annotations

import argparse

from pairing_validation import (  # studies/ is on sys.path
    SEEDS,
    add_kinds_and_smoke,
    check_kinds,
    print_table,
    score_seeds,
)

from aerodock.experiments.real_data import follower_vehicle
from aerodock.learning.datafiles import load_data_paths

SMOKE_EPOCHS = 10
"""``--smoke``'s epoch limit."""


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    for name in ("ss_train", "sl_train", "ss_test", "sl_test"):
        parser.add_argument(name)
    add_kinds_and_smoke(parser, SMOKE_EPOCHS)
    args = parser.parse_args(argv)
    check_kinds(parser, args.kinds)
    # loaded together, as ``aerodock train --data ss_train.npz sl_train.npz`` does: a flight
    # without free-air samples borrows the bias of its vehicle's flights across both files
    fit = load_data_paths([args.ss_train, args.sl_train])
    sl_test = load_data_paths([args.sl_test])
    follower = follower_vehicle(sl_test)
    judged = {"ss 05-06": load_data_paths([args.ss_test]),
              "small under large": sl_test.subset(follower == "cf51"),
              "large under small": sl_test.subset(follower == "cf101")}
    seeds, options = ((0,), {"max_epochs": SMOKE_EPOCHS}) if args.smoke else (SEEDS, {})
    rows = {kind: score_seeds("HELDOUT", kind, kind, fit, judged, options, seeds)
            for kind in args.kinds}
    print_table(f"model, seeds {', '.join(map(str, seeds))}", rows)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
