"""The wake's torque on the follower: the real Crazyflie flights' (from their logged motor torques
and body rates) against the fitted jet's at the same states (aerodock/identify/wake_torque.py).

    .venv/bin/python studies/wake_torque.py [--data $AERODOCK_DATA_DIR/neural-swarm] [--json]
        [--figure docs/figures/wake_torque.png]
        [--smoke]    # accepted for the suite: the study reads data only and takes seconds

The jet is examples/crazyflie_small_under_large.toml's (the fitted wake, cf101's fitted rotors);
the inertias are that file's: the small Crazyflie's [vehicle] and the large cf101's [leader]
(the small one's scaled by mass and the logged arm: an assumption). The samples are 0.15-0.45 m
below the other vehicle, binned by the horizontal offset from its axis (2 cm), out to 30 cm.
Beside the torque: the downward force by offset below the other vehicle and, as a control
without a wake, above it (0.15-0.45 m; 0.45-0.80 m, where the small follower flew under the
large leader), and the thrust map's slope in free air against the accelerometer. Then the same
torque and force from the motors' commands as sent (aerodock/identify/motor_commands.py: each
motor's map of its command fitted per flight, the thrust asked for beyond its ceiling taken
away), and the torque by the angle between the line to the axis and the nearest motor arm, as
asked for and as sent.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import asdict
from pathlib import Path

import numpy as np
from _smoke import add_smoke_option  # studies/, on sys.path

from aerodock.config import load_config
from aerodock.experiments.swap_flights import read_swap_flights
from aerodock.fileio import dumps_json, json_ready
from aerodock.identify.flights import WakeFitError, prepare_flights
from aerodock.identify.motor_commands import (
    CEILING_PWM,
    MAP_FIT_PWM,
    MotorMap,
    ceiling_by_vehicle,
    logs_as_sent,
)
from aerodock.identify.wake_torque import (
    disk_profile_torque,
    force_profile,
    free_air_map_check,
    motor_command_range,
    thrust_map_slope,
    torque_by_motor_angle,
    torque_profile,
)
from aerodock.ingest.data_dir import find_data_dir
from aerodock.plots import plot_torque_profile

ROOT = Path(__file__).resolve().parents[1]
# The data location (aerodock.ingest.data_dir): AERODOCK_DATA_DIR, else ../shared/data.
DATA_DIR = find_data_dir().path or ROOT.parent / "shared" / "data"
WORLD = ROOT / "examples" / "crazyflie_small_under_large.toml"
MAX_OFFSET_M = 0.30
FORCE_SEPARATIONS_M = ((0.15, 0.45), (0.45, 0.80))
PRINTED_DISK_OFFSET_M = 0.12  # the disk profile's torque is printed out to this offset
PRINTED_FORCE_OFFSETS_M = (0.0, 0.04, 0.08, 0.14, 0.18, 0.22)  # the force as sent, printed there


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path,
                        default=DATA_DIR / "neural-swarm")
    parser.add_argument("--json", action="store_true", help="print the results as JSON")
    parser.add_argument("--figure", type=Path,
                        help="draw the torque by offset and its lever (PNG) here")
    add_smoke_option(parser)
    args = parser.parse_args()
    try:
        logs = read_swap_flights(args.data)
    except FileNotFoundError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    cfg = load_config(WORLD)
    params = dict(cfg.downwash.params)
    inertia = {"cf50": cfg.vehicle.inertia_kgm2, "cf51": cfg.vehicle.inertia_kgm2,
               "cf101": cfg.leader.inertia_kgm2}
    radii = {"cf101": cfg.leader.rotor_radius_m}
    # the labels as asked for and, from the motors' commands as sent
    # (aerodock/identify/motor_commands.py), with the thrust the firmware asked for beyond a
    # motor's ceiling taken away, torque and force alike: each set's samples prepared once
    sent_logs, maps = logs_as_sent(logs)
    labels = {"asked": (logs, prepare_flights(logs)),
              "sent": (sent_logs, prepare_flights(sent_logs))}
    profile, sent = (torque_profile(params, flights, some, inertia, rotor_radii_m=radii,
                                    max_offset_m=MAX_OFFSET_M, hub_moments=True)
                     for some, flights in labels.values())
    forces = {sep: force_profile(logs, separation_m=sep) for sep in FORCE_SEPARATIONS_M}
    slopes = thrust_map_slope(logs)
    near = forces[FORCE_SEPARATIONS_M[0]]
    carried = {}
    for pair, bins in profile.items():
        try:  # a pairing without enough offset bins below the other vehicle has no fit
            carried[pair] = disk_profile_torque(near.get(pair, []), bins)
        except WakeFitError:
            pass
    sent_force = force_profile(sent_logs, separation_m=FORCE_SEPARATIONS_M[0])
    # the torque by where the motors point, as asked for and as sent
    by_angle = {name: torque_by_motor_angle(params, flights, some, inertia, rotor_radii_m=radii)
                for name, (some, flights) in labels.items()}
    commands = motor_command_range(logs)
    if args.figure is not None:
        plot_torque_profile(profile, sent, args.figure)
    map_check = free_air_map_check(logs)
    # The world's attitude loop read as a spring: J times its angle gain times its rate gain.
    ap = cfg.autopilot
    world_nm_per_rad = float(cfg.vehicle.inertia_kgm2[0] * ap.attitude_p[0] * ap.rate_p[0])
    if args.json:
        print(dumps_json(json_ready({
            "profile": {pair: [{**asdict(b), "nm_per_rad": b.nm_per_rad, "lever_m": b.lever_m,
                                "lever_bound_m": b.lever_bound_m} for b in bins]
                        for pair, bins in profile.items()},
            "force_profile": {f"{lo:.2f}-{hi:.2f} m": {pair: [asdict(b) for b in bins]
                                                        for pair, bins in by_pair.items()}
                              for (lo, hi), by_pair in forces.items()},
            "thrust_map_slope": slopes,
            "disk_profile": {pair: {"torque_nm": torque.tolist(), "params": fitted}
                             for pair, (torque, fitted) in carried.items()},
            "motor_commands": commands, "free_air_map_check": map_check,
            "world_small_nm_per_rad": world_nm_per_rad,
            "as_sent": {"profile": {pair: [{**asdict(b), "lever_m": b.lever_m} for b in bins]
                                    for pair, bins in sent.items()},
                        "force_profile": {pair: [asdict(b) for b in bins]
                                          for pair, bins in sent_force.items()},
                        "motor_maps": [asdict(m) for m in maps]},
            "by_motor_angle": {name: {pair: [asdict(b) for b in bins]
                                      for pair, bins in rows.items()}
                               for name, rows in by_angle.items()}})))
        return 0
    for pair, bins in profile.items():
        if not bins:
            print(f"{pair} (follower under leader): no offset bin with enough samples in the band "
                  "(flights with free air to take the trim from)")
            continue
        print(f"{pair} (follower under leader), inward wake torque, mN m:")
        print("  offset [cm]  samples  real (se)       jet    real/jet  lever [cm]  "
              "lean in [deg]  nearest motor's PWM  real torque/lean [mN m/rad]  "
              "real moving in / out")
        for b in bins:
            pwm = "-" if b.near_motor_pwm is None else f"{b.near_motor_pwm:.2f}"
            print(f"  {100 * b.offset_lo_m:4.0f}-{100 * b.offset_hi_m:<4.0f}  {b.samples:7d}  "
                  f"{1e3 * b.real_nm:6.2f} ({1e3 * b.real_se_nm:.2f})  {1e3 * b.jet_nm:6.2f}  "
                  f"{b.ratio:8.1f}  {100 * b.lever_m:10.1f}  {b.lean_in_deg:13.1f}  {pwm:>19}  "
                  f"{1e3 * b.nm_per_rad:10.0f}  {1e3 * b.real_moving_in_nm:17.2f} / "
                  f"{1e3 * b.real_moving_out_nm:.2f}")
        print(f"  (a loss of thrust on the disks alone: lever at most the half diagonal, "
              f"{100 * bins[0].half_diagonal_m:.1f} cm, with each disk's force at its hub; "
              f"{100 * bins[0].lever_bound_m:.1f} cm however it is spread over the disks)")
    linear = torque_profile(params, labels["asked"][1], logs, inertia, rotor_radii_m=radii,
                            max_offset_m=MAX_OFFSET_M, hub_moments=True, hub_exponent=1.0)
    print_hub_moments(profile, "the jet's own ingest law")
    print_hub_moments(linear, "a load linear in the inflow (blade-element theory)")
    for vid, c in commands.items():
        print(f"{vid}'s motor commands: {c['free_air_median']:.2f} median in free air, "
              f"{c['p99']:.2f} at the 99th percentile of every flight")
    print("free air, the vertical residual [m/s^2, down +] by the highest motor's command:")
    for vid, rows in map_check.items():
        cells = ", ".join(f"{r['pwm_lo']:.2f}-{r['pwm_hi']:.2f}: "
                          f"{r['vertical_residual_mps2']:+.3f} ({r['samples']})" for r in rows)
        print(f"  {vid}: {cells}")
    print("the downward force by offset [mN (se)], below the other vehicle / above it (a control "
          "without a wake):")
    for (lo, hi), by_pair in forces.items():
        for pair, bins in by_pair.items():
            if not any(np.isfinite(b.below_n) for b in bins):
                continue
            print(f"  {pair}, {lo:.2f}-{hi:.2f} m apart:")
            for b in bins:
                print(f"    {100 * b.offset_lo_m:4.0f}-{100 * b.offset_hi_m:<4.0f}  "
                      f"{_cell(b.below_n, b.below_se_n)}  /  {_cell(b.above_n, b.above_se_n)}")
    print("the torque the force would make on the disks alone (a core-and-ring disk profile "
          "fitted to the force by offset), mN m, and the real over it:")
    for pair, (torque, fitted) in carried.items():
        cells = ", ".join(f"{100 * b.offset_lo_m:.0f}-{100 * b.offset_hi_m:.0f}: "
                          f"{1e3 * t:.2f} ({b.real_nm / t:.1f}x)"
                          for b, t in zip(profile[pair], torque, strict=True)
                          if b.offset_hi_m <= PRINTED_DISK_OFFSET_M + 1e-9)
        ring = (f"ring {1e3 * fitted['core_n'] * fitted['ring_fraction']:.1f} mN per disk "
                f"at {100 * fitted['ring_radius_m']:.0f} cm")
        print(f"  {pair}: {cells} ({ring})")
    print("the thrust map's slope in free air (the accelerometer's thrust on the logged, "
          "0.5-4 Hz; forward and reverse bracket it):")
    for vid, r in slopes.items():
        print(f"  {vid}: {r['forward']:.2f}-{r['reverse']:.2f} (correlation "
              f"{r['correlation']:.2f}, lag {1e3 * r['delay_s']:.0f} ms, {r['samples']} samples)")
    print_as_sent(profile, sent, sent_force, maps)
    print("the inward torque 4-10 cm off the axis by the angle between the line to the axis and "
          "the nearest motor arm (0: a motor on it), mN m, real (se) / jet:")
    for name, rows in by_angle.items():
        for pair, bins in rows.items():
            if bins:
                cells = ", ".join(f"{b.angle_lo_deg:.0f}-{b.angle_hi_deg:.0f} deg: "
                                  f"{1e3 * b.real_nm:.2f} ({1e3 * b.real_se_nm:.2f}) / "
                                  f"{1e3 * b.jet_nm:.2f}" for b in bins)
                print(f"  {name}, {pair}: {cells}")
    print(f"the small Crazyflie world's attitude loop as a spring (J x angle gain x rate gain): "
          f"{1e3 * world_nm_per_rad:.1f} mN m/rad")
    return 0


def print_hub_moments(profile: dict, law: str) -> None:
    """The jet's load spread over each disk (its moments about the hubs) beside its disk
    torque and the real one, out to the printed offset."""
    print(f"the jet's axial load spread over each disk, not put at its hub (hub_moments_nm, "
          f"{law}): its inward moments about the hubs, mN m, their share of the jet's disk "
          f"torque, and the real torque over both:")
    for pair, bins in profile.items():
        cells = ", ".join(f"{100 * b.offset_lo_m:.0f}-{100 * b.offset_hi_m:.0f}: "
                          f"{1e3 * b.hub_nm:.2f} ({100 * b.hub_nm / b.jet_nm:.0f} %, real "
                          f"{b.real_nm / (b.jet_nm + b.hub_nm):.1f}x)"
                          for b in bins if b.offset_hi_m <= PRINTED_DISK_OFFSET_M + 1e-9)
        if cells:
            print(f"  {pair}: {cells}")


def print_as_sent(asked: dict, sent: dict, sent_force: dict, maps: list[MotorMap]) -> None:
    """The torque and force from the motors' commands as sent, beside the asked-for ones."""
    print(f"the motors' command maps (each motor's asked-for thrust on its command and the "
          f"battery's voltage, fitted where every command is below {MAP_FIT_PWM}), per vehicle: "
          f"the largest residual sd, and the thrust asked for beyond the map's at commands of "
          f"{CEILING_PWM} and up:")
    for row in ceiling_by_vehicle(maps):
        print(f"  {row['vehicle']}: {row['flights']} flights, residual sd up to "
              f"{1e3 * row['residual_sd_n']:.1f} mN; {row['ceiling_samples']} motor samples at "
              f"the ceiling (commands up to {row['top_pwm']:.3f}), "
              f"{1e3 * row['ceiling_excess_n']:.1f} mN asked beyond the map there")
    print("the inward wake torque from the commands as sent, mN m: asked-for / as sent / jet, "
          "as sent over the jet, the lever as sent [cm] (its force as sent too):")
    for pair, bins in sent.items():
        before = {(b.offset_lo_m, b.offset_hi_m): b for b in asked.get(pair, [])}
        for b in bins:
            a = before.get((b.offset_lo_m, b.offset_hi_m))
            if a is None or b.offset_hi_m > PRINTED_DISK_OFFSET_M + 1e-9:
                continue
            print(f"  {pair} {100 * b.offset_lo_m:4.0f}-{100 * b.offset_hi_m:<4.0f} "
                  f"{1e3 * a.real_nm:6.2f} / {1e3 * b.real_nm:6.2f} / {1e3 * b.jet_nm:5.2f}  "
                  f"{b.ratio:5.1f}  {100 * b.lever_m:6.1f}")
    print("the downward force below the other vehicle from the commands as sent, 0.15-0.45 m "
          "apart [mN (se)]:")
    for pair, bins in sent_force.items():
        cells = ", ".join(f"{100 * b.offset_lo_m:.0f}-{100 * b.offset_hi_m:.0f}: "
                          f"{_cell(b.below_n, b.below_se_n).strip()}" for b in bins
                          if np.isfinite(b.below_n) and b.offset_lo_m in PRINTED_FORCE_OFFSETS_M)
        print(f"  {pair}: {cells}")


def _cell(mean_n: float, se_n: float) -> str:
    return f"{1e3 * mean_n:6.1f} ({1e3 * se_n:.1f})" if np.isfinite(mean_n) else " " * 12


if __name__ == "__main__":
    raise SystemExit(main())
