"""The flight stacks' attitude loops: their step responses, and how stiffly the Crazyflie world's
follower holds the wake's torque beside the real Neural-Swarm flights (issue 39, items 1-2).

    .venv/bin/python studies/attitude_stacks.py [--data $AERODOCK_DATA_DIR/neural-swarm]
        [--flights 8] [--swaps 40] [--torque-gain 1] [--json] [--smoke]

Step: a 5 deg roll step from hover, one exactly nominal vehicle, the ideal IMU chain; the fraction
of the step reached at 0.05, 0.1 and 0.2 s and the peak, each stack on its vehicle (the paper's
for ``generic`` and ``arducopter``, examples/crazyflie.toml for the Crazyflie stacks, and
``generic-fitted``: the generic loop with the gains the Crazyflie world flew before, fitted to
drone-models' identified step response).

Hover: 16 followers of the Crazyflie world (each vehicle drawn from the world's spread, the
filtered IMU chain) holding station in free air for 3 s under the tuned controller, with each
Crazyflie stack: how many end more than 0.2 m from where they were held.

Under the wake (``--data`` given or found): per pairing of the shared flights (small under small:
examples/crazyflie.toml; small under large: examples/crazyflie_small_under_large.toml; large under
small: examples/crazyflie_large_under_small.toml), the follower's inward wake torque, its lean into
the leader's axis and their ratio (N m per radian of lean: an apparent stiffness, the lean being
the position loop's too) per 2 cm bin of horizontal offset, 4-10 cm, read by the same code
(:func:`aerodock.identify.wake_torque.torque_profile`) from the real flights and from the world's
wake-excitation flights (the sim-to-real study's, :func:`aerodock.experiments.sim_to_real.
simulated_flights`) flown with each stack, and from the world flying the real flights' own
manoeuvre (``--swaps`` flights of the swap task, :mod:`aerodock.collect.swaps`; their trim taken as
the real flights', in free air 0.4 m to the side). The simulated logs' rotor torque (what the
rotors explain from their speeds) stands for the real logs' motor torque (the Crazyflie's own mixer
of its per-motor thrust estimates). ``--torque-gain`` scales the world's wake torque
(``disk_torque_gain``). And per pairing, 0-16 cm off the axis, the inward torque while the
follower moves in towards the leader's axis and while it moves out, real and the world's swap
task (the real flights' torque depends on the direction of motion; the world's barely does).
And per pairing, the follower's attitude loop read from its logs, 2-6 Hz
(:mod:`aerodock.identify.attitude_loop`: the commanded torque's stiffness, damping and
rate-derivative term), real and the world's swap task, beside the configured SJC law's.
``--smoke``: the step of ArduCopter, the hover of the stock PID (two
vehicles, 0.5 s), its flights under the wake (one flight in one band, two swaps).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
from _smoke import add_smoke_option  # studies/, on sys.path
from crazyflie_autopilot_fit import step_response  # the 5 deg roll step, as fitted there

from aerodock.config import Config, load_config
from aerodock.downwash import build_field
from aerodock.ingest.data_dir import find_data_dir
from aerodock.rng import TrialRNG
from aerodock.world import World

ROOT = Path(__file__).resolve().parents[1]
DATA_DIR = find_data_dir().path or ROOT.parent / "shared" / "data"
CRAZYFLIE = ROOT / "examples" / "crazyflie.toml"
WORLDS = {"32 g under 32 g": (CRAZYFLIE, "swap_ss", None),
          "32 g under 67 g": (ROOT / "examples" / "crazyflie_small_under_large.toml",
                              "swap_sl_2020-06-19", "cf51=small,cf101=large"),
          "67 g under 32 g": (ROOT / "examples" / "crazyflie_large_under_small.toml",
                              "swap_sl_2020-06-19", "cf51=small,cf101=large")}
# (follower, leader) sizes of each pairing: the swap task's separations for its simulated swaps
SIZES = {"32 g under 32 g": ("small", "small"), "32 g under 67 g": ("small", "large"),
         "67 g under 32 g": ("large", "small")}
# The generic autopilot as the Crazyflie world flew it before the flight stacks: gains fitted to
# drone-models' identified step response (studies/crazyflie_autopilot_fit.py).
GENERIC_FITTED = {"stack": "generic", "attitude_p": [10.3, 10.3, 7.9],
                  "rate_p": [26.3, 26.3, 28.6], "rate_i": [11.7, 11.7, 9.5]}
STEP_STACKS = (("generic", None), ("arducopter", None), ("generic-fitted", CRAZYFLIE),
               ("crazyflie-pid", CRAZYFLIE), ("crazyflie-sjc", CRAZYFLIE))
CF_STACKS = ("generic-fitted", "crazyflie-pid", "crazyflie-sjc")


def _autopilot(stack: str) -> dict:
    """The ``[autopilot]`` overrides of a row's stack (``generic-fitted``: see above)."""
    return dict(GENERIC_FITTED) if stack == "generic-fitted" else {"stack": stack}
BINS_M = (0.04, 0.06, 0.08)


def step_rows(stacks) -> list[dict]:
    rows = []
    for stack, path in stacks:
        cfg = load_config(path).with_overrides({"autopilot": _autopilot(stack)})
        t, roll = step_response(cfg)
        at = {f"{s:g}s": float(np.interp(s, t, roll)) for s in (0.05, 0.1, 0.2)}
        rows.append({"stack": stack, "vehicle": "crazyflie" if path else "paper",
                     **at, "peak": float(roll.max())})
    return rows


HOVER_CASES = (("crazyflie-pid", {}), ("crazyflie-sjc", {}))


def hover_losses(stack: str, overrides: dict, n: int = 16, seconds: float = 3.0) -> int:
    """How many of ``n`` followers holding station in free air end more than 0.2 m off."""
    from aerodock.control.controller import PositionController, Reference
    from aerodock.mission.settle import reset_controllers

    cfg = load_config(CRAZYFLIE).with_overrides({"autopilot": {"stack": stack}, **overrides})
    world = World(cfg, n, TrialRNG(0, n), field=build_field(cfg))
    lead_p, fol_p = np.tile([0.0, 0.0, -2.5], (n, 1)), np.tile([3.0, 0.0, -2.5], (n, 1))
    world.reset(lead_p, fol_p)
    lead_ctl, fol_ctl = (PositionController(cfg, n, use_observer=True) for _ in range(2))
    reset_controllers(world, lead_ctl, fol_ctl)
    zero = np.zeros((n, 3))
    refs = [Reference(p, zero, zero, np.zeros(n), np.zeros(n)) for p in (lead_p, fol_p)]
    for _ in range(int(round(seconds / world.dt_control_s))):
        obs_l, obs_f = world.observe()
        world.advance(lead_ctl.step(obs_l.p, obs_l.v, obs_l.rpy, refs[0]).command,
                      fol_ctl.step(obs_f.p, obs_f.v, obs_f.rpy, refs[1]).command)
    return int((np.linalg.norm(world.follower.p - fol_p, axis=1) > 0.2).sum())


def _torque_bins(logs, cfg: Config, pair: str, free_air_m: float,
                 separation_m: tuple[float, float]) -> list:
    """The pairing's inward torque profile (:func:`aerodock.identify.wake_torque.torque_profile`
    with the world's jet and inertia) over the samples ``separation_m`` below the leader."""
    from aerodock.identify import flights as fl
    from aerodock.identify.field_score import scaled_inertia
    from aerodock.identify.wake_torque import torque_profile

    flights = fl.prepare_flights(logs)
    inertia = scaled_inertia(flights, cfg.vehicle.mass_kg, cfg.vehicle.diagonal_m,
                             cfg.vehicle.inertia_kgm2)
    profile = torque_profile(dict(cfg.downwash.params), flights, logs, inertia,
                             separation_m=separation_m, free_air_offset_m=free_air_m)
    return profile.get(pair, [])


def _torque_rows(logs, cfg: Config, pair: str, free_air_m: float) -> dict[float, dict]:
    """Per offset bin: inward torque (mN m), lean into the axis (deg), and their ratio."""
    out = {}
    for b in _torque_bins(logs, cfg, pair, free_air_m, (0.1, 0.7)):
        if any(abs(b.offset_lo_m - lo) < 1e-9 for lo in BINS_M):
            out[round(b.offset_lo_m, 2)] = {"torque_mnm": 1e3 * b.real_nm,
                                            "lean_deg": b.lean_in_deg,
                                            "mnm_per_rad": 1e3 * b.nm_per_rad,
                                            "samples": b.samples}
    return out


def _in_out_rows(logs, cfg: Config, pair: str,
                 free_air_m: float) -> dict[float, list[float | None]]:
    """Per 2 cm offset bin, 0-16 cm, 0.15-0.45 m below: the inward torque (mN m) while the
    follower moves in towards the leader's axis and while it moves out (None: too few
    samples)."""
    return {round(b.offset_lo_m, 2): [1e3 * x if math.isfinite(x) else None
                                      for x in (b.real_moving_in_nm, b.real_moving_out_nm)]
            for b in _torque_bins(logs, cfg, pair, free_air_m, (0.15, 0.45))}


def _loop_cells(responses) -> dict[str, list[float | None]]:
    """Per axis, an attitude loop (read from logs, or a law's: R^2 None) as the study prints it:
    stiffness mN m/rad, damping mN m s/rad, rate-derivative term uN m s^2/rad, R^2."""
    return {r.axis: [1e3 * r.stiffness_nm_per_rad, 1e3 * r.damping_nms_per_rad,
                     1e6 * r.rate_dot_nms2_per_rad, None if math.isnan(r.r2) else r.r2]
            for r in responses}


def _as_motor_torque(logs):
    """Simulated logs with their rotor torque where the real logs carry the motors'."""
    from aerodock.identify.wake_torque import MOTOR_TORQUE_KEY

    return [replace(lg, extra={**lg.extra,
                               MOTOR_TORQUE_KEY: lg.extra["follower_rotor_torque_nm"]})
            for lg in logs]


def wake_rows(data: Path, flights: int, swaps: int, torque_gain: float,
              smoke: bool) -> list[dict]:
    from aerodock.collect.swaps import SWAP_SEPARATIONS_M, swap_task_flights
    from aerodock.experiments.sim_to_real import simulated_flights
    from aerodock.identify.attitude_loop import loop_response, sjc_law_response
    from aerodock.identify.wake_torque import FREE_AIR_OFFSET_M, MOTOR_TORQUE_KEY
    from aerodock.ingest import read_logs
    from aerodock.learning.labels import ROTOR_TORQUE_KEY

    rows = []
    for pair, (path, folder, vehicles) in WORLDS.items():
        if smoke and pair != "32 g under 32 g":
            continue
        base = load_config(path)
        real = read_logs("neural-swarm", [data / folder],
                         **({"vehicle": vehicles} if vehicles else {}))
        entry = {"pair": pair, "real": _torque_rows(real, base, pair, FREE_AIR_OFFSET_M),
                 "world": {}, "world_swaps": {},
                 "in_out": {"real": _in_out_rows(real, base, pair, FREE_AIR_OFFSET_M)},
                 # the pairing's follower's own logs only (the folder holds the other's too)
                 "loop": {"real": _loop_cells(loop_response([lg for lg in real if math.isclose(
                     lg.meta.get("follower_mass_kg", 0.0), base.vehicle.mass_kg)],
                                                            MOTOR_TORQUE_KEY)),
                          "the SJC law, its gains": _loop_cells(sjc_law_response(
                              base.autopilot))}}
        for stack in CF_STACKS[1:2] if smoke else CF_STACKS:
            cfg = base.with_overrides({"autopilot": _autopilot(stack),
                                       "downwash": {"params": {"disk_torque_gain":
                                                               torque_gain}}})
            logs = simulated_flights(cfg, flights_per_band=flights,
                                     bands=(0,) if smoke else None)
            # the flights' free-air waypoints are curriculum.free_air_m to the side
            entry["world"][stack] = _torque_rows(_as_motor_torque(logs), cfg, pair,
                                                 0.8 * cfg.curriculum.free_air_m)
            # the same manoeuvre as the real flights: the swap task, its trim read as theirs
            swap_logs = swap_task_flights(cfg, swaps, SWAP_SEPARATIONS_M[SIZES[pair]], seed=0,
                                          free_air_radius_m=FREE_AIR_OFFSET_M, name="swap")
            entry["world_swaps"][stack] = _torque_rows(_as_motor_torque(swap_logs), cfg, pair,
                                                       FREE_AIR_OFFSET_M)
            entry["in_out"][f"{stack}, swaps"] = _in_out_rows(_as_motor_torque(swap_logs), cfg,
                                                              pair, FREE_AIR_OFFSET_M)
            entry["loop"][f"{stack}, swaps"] = _loop_cells(loop_response(swap_logs,
                                                                         ROTOR_TORQUE_KEY))
        rows.append(entry)
    return rows


def _mnm(torque_mnm: float | None) -> str:
    """A torque in mN m as the tables print it ("-": too few samples)."""
    return "-" if torque_mnm is None else f"{torque_mnm:.2f}"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=DATA_DIR / "neural-swarm")
    parser.add_argument("--flights", type=int, default=8, help="simulated flights per band")
    parser.add_argument("--swaps", type=int, default=40,
                        help="simulated flights of the swap task per pairing and stack")
    parser.add_argument("--torque-gain", type=float, default=1.0)
    parser.add_argument("--json", action="store_true")
    add_smoke_option(parser)
    args = parser.parse_args()
    if args.flights < 1 or args.swaps < 1:
        parser.error("--flights and --swaps must be 1 or more")
    steps = step_rows(STEP_STACKS[1:2] if args.smoke else STEP_STACKS)
    hover = [{"stack": stack, "overrides": over,
              "lost": hover_losses(stack, over, n=2 if args.smoke else 16,
                                   seconds=0.5 if args.smoke else 3.0)}
             for stack, over in (HOVER_CASES[:1] if args.smoke else HOVER_CASES)]
    wake = (wake_rows(args.data, 1 if args.smoke else args.flights,
                      2 if args.smoke else args.swaps, args.torque_gain, args.smoke)
            if args.data.is_dir() else [])
    if args.json:
        print(json.dumps({"step": steps, "hover": hover, "wake": wake}, indent=2))
        return 0
    print("5 deg roll step, fraction reached at 0.05 / 0.1 / 0.2 s, peak:")
    for r in steps:
        print(f"  {r['stack']:<14} {r['vehicle']:<10} {r['0.05s']:.2f} / {r['0.1s']:.2f} / "
              f"{r['0.2s']:.2f}, peak {r['peak']:.2f}")
    print(f"hovering {0.5 if args.smoke else 3} s in free air, followers lost (> 0.2 m off) of "
          f"{2 if args.smoke else 16}:")
    for r in hover:
        how = json.dumps(r["overrides"]) if r["overrides"] else "as configured"
        print(f"  {r['stack']:<14} {how}: {r['lost']}")
    if not wake:
        print(f"no flights at {args.data}: the wake part skipped")
    for entry in wake:
        print(f"{entry['pair']}: inward torque mN m, lean deg, mN m per rad, per offset bin")
        for who, bins in ([("real", entry["real"])] + list(entry["world"].items())
                          + [(f"{stack}, swaps", b) for stack, b in entry["world_swaps"].items()]):
            cells = "; ".join(f"{100 * lo:.0f}-{100 * lo + 2:.0f} cm {b['torque_mnm']:.2f} / "
                              f"{b['lean_deg']:.1f} / {b['mnm_per_rad']:.0f}"
                              for lo, b in sorted(bins.items()))
            print(f"  {who:<21} {cells or 'no bin with samples'}")
        print(f"{entry['pair']}, 0.15-0.45 m below: inward torque mN m moving in / moving out, "
              "per offset bin")
        for who, bins in entry["in_out"].items():
            cells = "; ".join(f"{100 * lo:.0f}-{100 * lo + 2:.0f} cm {_mnm(i)} / {_mnm(o)}"
                              for lo, (i, o) in sorted(bins.items()))
            print(f"  {who:<21} {cells or 'no bin with samples'}")
        print(f"{entry['pair']}: the follower's attitude loop, 2-6 Hz, roll; pitch: stiffness "
              "mN m/rad / damping mN m s/rad / rate-derivative uN m s^2/rad (R^2)")
        for who, axes in entry["loop"].items():
            cells = "; ".join(f"{k:.1f} / {c:.2f} / {d:.0f}"
                              + (f" ({r2:.2f})" if r2 is not None else "")
                              for k, c, d, r2 in axes.values())
            print(f"  {who:<21} {cells}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
