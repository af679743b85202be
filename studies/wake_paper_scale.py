"""The default wake on the paper's 0.7 kg vehicles, measured the same way for any aerodock: mean
downward acceleration on a level follower directly below a hovering leader, its half-magnitude
radius, and the sd and correlation time of the turbulence there (from consecutive samples at the
physics rate, through the public ``field probe`` functions only, so an older aerodock measures
alike); and the mean torque on the follower's rotor disks 0.36 m below, 5, 10 and 15 cm off the
axis (``mean_disk_torque_nm``, turbulence off).

    .venv/bin/python studies/wake_paper_scale.py [--samples 40000] [--json]
        [--smoke]    # 2,000 samples a separation
    # the previous release's hand-calibrated jet, for the comparison in docs/world.md:
    git archive 609b0bc aerodock | tar -x -C /tmp/before
    PYTHONPATH=/tmp/before .venv/bin/python studies/wake_paper_scale.py
"""

from __future__ import annotations

import argparse
import json

import numpy as np
from _smoke import add_smoke_option  # studies/, on sys.path

from aerodock.config import load_config
from aerodock.downwash import build_field
from aerodock.downwash.probe import half_magnitude_radius_m, probe_bodies, probe_field

SEPARATIONS_M = (0.36, 0.64, 1.35)
TORQUE_OFFSETS_M = (0.05, 0.10, 0.15)


def measure(samples: int, seed: int) -> list[dict]:
    cfg = load_config()
    mass, g, dt = cfg.vehicle.mass_kg, cfg.sim.gravity_mps2, 1.0 / cfg.sim.physics_rate_hz
    rows = []
    for sep in SEPARATIONS_M:
        field = build_field(cfg)
        field.reset(1, np.random.default_rng(seed))
        leader, follower = probe_bodies(sep, 0.0, 0.0, mass, g)
        draws = np.array([field.acceleration(leader, follower, dt)[0] for _ in range(samples)])
        dev = draws[:, 2] - draws[:, 2].mean()
        corr = [np.dot(dev[:-k], dev[k:]) / np.dot(dev, dev) for k in range(1, 200)]
        below = next((k for k, c in enumerate(corr, 1) if c < np.exp(-1.0)), None)
        mean = probe_field(build_field(cfg), sep, 0.0, 0.0, 2, dt, np.random.default_rng(seed),
                           mass, g)["field_mean_mps2"]
        rows.append({
            "separation_m": sep, "mean_mps2": mean[2],
            "half_width_m": half_magnitude_radius_m(build_field(cfg).mean_acceleration, sep,
                                                    mass, g),
            "vertical_sd_mps2": float(draws[:, 2].std()),
            "lateral_sd_mps2": float(0.5 * (draws[:, 0].std() + draws[:, 1].std())),
            "corr_time_s": None if below is None else below * dt,
        })
    return rows


def disk_torques(separation_m: float = 0.36) -> list[dict]:
    """The mean torque (N m, its magnitude) of the wake on a level follower's disks
    ``separation_m`` below a hovering leader, at :data:`TORQUE_OFFSETS_M` off its axis."""
    cfg = load_config()
    mass, g = cfg.vehicle.mass_kg, cfg.sim.gravity_mps2
    field = build_field(cfg)
    rows = []
    for off in TORQUE_OFFSETS_M:
        leader, follower = probe_bodies(separation_m, off, 0.0, mass, g)
        torque = field.mean_disk_torque_nm(leader, follower)[0]
        rows.append({"separation_m": separation_m, "offset_m": off,
                     "disk_torque_nm": float(np.linalg.norm(torque))})
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=40000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", action="store_true")
    add_smoke_option(parser)
    args = parser.parse_args()
    rows = measure(2000 if args.smoke else args.samples, args.seed)
    torques = disk_torques()
    if args.json:
        print(json.dumps({"below": rows, "disk_torque": torques}, indent=2))
        return
    print("| separation | mean [m/s²] | half-width [m] | vertical sd [m/s²] | "
          "lateral sd [m/s²] | correlation time [s] |")
    print("| --- | --- | --- | --- | --- | --- |")
    for r in rows:
        tau = "n/a" if r["corr_time_s"] is None else f"{r['corr_time_s']:.3f}"
        print(f"| {r['separation_m']:.2f} m | {r['mean_mps2']:.2f} | {r['half_width_m']:.3f} | "
              f"{r['vertical_sd_mps2']:.2f} | {r['lateral_sd_mps2']:.2f} | {tau} |")
    print("the disks' mean torque 0.36 m below, N m: " + ", ".join(
        f"{100 * r['offset_m']:.0f} cm off the axis {r['disk_torque_nm']:.3f}" for r in torques))


if __name__ == "__main__":
    main()
