"""The wake's turbulence read above the labels' noise at the follower's own speed, on the real
Crazyflie flights (aerodock/identify/label_noise.py), beside the fit's pooled reading.

    .venv/bin/python studies/label_noise_speed.py [--data $AERODOCK_DATA_DIR/neural-swarm] [--json]
        [--smoke]    # accepted for the suite: the study reads data only and takes seconds

The jet is examples/crazyflie_wake_fitted.toml's, the flights the fit's: swap_ss 00-04 and
swap_sl 00-07 fitted on, swap_ss 05-06 and swap_sl 08-11 held out (docs/world.md).
"""

from __future__ import annotations

import argparse
import json
import sys
import tomllib
from pathlib import Path

from _smoke import add_smoke_option  # studies/, on sys.path

from aerodock.experiments.swap_flights import read_swap_flights
from aerodock.identify.flights import prepare_flights, select_flights
from aerodock.identify.label_noise import noise_by_speed, speed_matched_turbulence
from aerodock.ingest.data_dir import find_data_dir

ROOT = Path(__file__).resolve().parents[1]
# The data location (aerodock.ingest.data_dir): AERODOCK_DATA_DIR, else ../shared/data.
DATA_DIR = find_data_dir().path or ROOT.parent / "shared" / "data"
FIT = ROOT / "examples" / "crazyflie_wake_fitted.toml"
HOLDOUT = ("swap_ss_0[56]", "swap_sl_2020-06-19_0[89]", "swap_sl_2020-06-19_1[01]")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path,
                        default=DATA_DIR / "neural-swarm")
    parser.add_argument("--json", action="store_true")
    add_smoke_option(parser)
    args = parser.parse_args()
    try:
        logs = read_swap_flights(args.data)
    except FileNotFoundError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    params = tomllib.loads(FIT.read_text())["downwash"]["params"]
    noise = noise_by_speed(logs)
    train, held = select_flights(prepare_flights(logs), HOLDOUT)
    out = {"noise": {vid: {"edges_mps": list(t.edges_mps), "samples": t.samples.tolist(),
                           "lateral_sd": [float((0.5 * (v[0] + v[1])) ** 0.5)
                                          for v in t.var_mps4],
                           "vertical_sd": [float(v[2] ** 0.5) for v in t.var_mps4]}
                     for vid, t in noise.items()},
           "held_out": speed_matched_turbulence(params, held, noise),
           "fitted_on": speed_matched_turbulence(params, train, noise)}
    if args.json:
        print(json.dumps(out, indent=2, default=float))
        return 0
    for vid, t in out["noise"].items():
        cells = ", ".join(f"{lo:g}-{hi:g}: {lat:.3f}/{vert:.3f} ({n})" for lo, hi, lat, vert, n in
                          zip(t["edges_mps"][:-1], t["edges_mps"][1:], t["lateral_sd"],
                              t["vertical_sd"], t["samples"], strict=True))
        print(f"{vid} free-air label noise sd, lateral/vertical m/s^2, by speed m/s: {cells}")
    for part in ("held_out", "fitted_on"):
        print(f"{part.replace('_', ' ')} flights, within one leader equivalent radius of the "
              "axis, turbulence sd m/s^2 (real less the pooled noise / less the noise at the "
              "follower's speed [95th pct over flights] / the jet's):")
        for pair, r in out[part].items():
            print(f"  {pair} ({r['samples']:.0f} samples, {r['flights']:.0f} flights, median speed "
                  f"{r['median_speed_mps']:.2f} m/s): lateral "
                  f"{r['lateral_pooled']:.3f} / {r['lateral_speed']:.3f} "
                  f"[{r['lateral_speed_p95']:.3f}] / {r['lateral_model']:.3f}; vertical "
                  f"{r['vertical_pooled']:.3f} / {r['vertical_speed']:.3f} "
                  f"[{r['vertical_speed_p95']:.3f}] / {r['vertical_model']:.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
