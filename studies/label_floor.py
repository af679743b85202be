"""The label's noise floor per follower: how much of it no wake model can explain (data only).

    .venv/bin/python studies/label_floor.py sl_train.npz sl_test.npz [--out-radius 0.3] [--json]
        [--smoke]    # accepted for the suite: the study reads data only and takes seconds

For each data set file (from ``aerodock ingest``) and each follower (the flight name's last
``_`` part, e.g. ``cf101``): the vertical label's RMS in the interaction region (the zero
model's RMSE) and out of the wake (below the leader, at least ``--out-radius`` off its axis), the
mean there, and the ceiling ``1 - rms_out / rms_wake`` on any wake model's reduction
(aerodock/experiments/label_floor.py says the assumptions).
"""

from __future__ import annotations

import argparse
import json

from _smoke import add_smoke_option  # studies/, on sys.path

from aerodock.experiments.label_floor import OUT_OF_WAKE_RADIUS_M, label_floor
from aerodock.experiments.real_data import follower_vehicle
from aerodock.learning.datafiles import load_data_paths


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", nargs="+", help="data set files (.npz), each judged apart")
    parser.add_argument("--out-radius", type=float, default=OUT_OF_WAKE_RADIUS_M,
                        help="horizontal distance out of the wake, m")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    add_smoke_option(parser)
    args = parser.parse_args()
    rows = []
    for path in args.data:
        ds = load_data_paths([path])
        follower = follower_vehicle(ds)
        for who in sorted(set(follower)):
            floor = label_floor(ds, follower == who, out_radius_m=args.out_radius)
            rows.append({"data": path, "follower": who, **floor.as_dict()})
    if args.json:
        print(json.dumps(rows, indent=1))
        return 0
    print(f"{'data':<16} {'follower':<8} {'n_wake':>6} {'rms_wake':>8} {'n_out':>6} "
          f"{'rms_out':>7} {'mean_out':>8} {'ceiling':>7}")
    for r in rows:
        if r["ceiling"] is None:
            print(f"{r['data']:<16} {r['follower']:<8} {r['n_wake']:>6} (no samples in one region)")
            continue
        print(f"{r['data']:<16} {r['follower']:<8} {r['n_wake']:>6} {r['rms_wake']:>8.3f} "
              f"{r['n_out']:>6} {r['rms_out']:>7.3f} {r['out_mean']:>+8.3f} "
              f"{100 * r['ceiling']:>6.1f}%")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
