"""The Neural-Swarm swap task, simulated: two vehicles on a circle swap sides through its centre.

The real flights that judge the simulator (``swap_ss``, ``swap_sl``) were flown by the
Neural-Swarm data-collection script (aerorobotics/neural-swarm ``hardware/neural-swarm-ros-pkg/
scripts/datacollection_swap.py``): each vehicle takes a random angle on a circle of radius
0.25 m (:data:`SWAP_RADIUS_M`) at its own height, the upper one above the lower by a separation
drawn per flight (:data:`SWAP_SEPARATIONS_M`, by which vehicle is large); then every vehicle flies
to the opposite point of its circle and back (Crazyswarm's ``goTo``, a straight line through the
centre), in 4, 3 and 2 s (:data:`SWAP_TIMES_S`), 0.1 s apart. Both vehicles cross the axis at
mid-swap, each along its own heading: the lower one passes under the upper one while both move,
in directions drawn independently (opposite, crossing, or alike).

The curriculum's wake-excitation flights (:mod:`aerodock.collect.curriculum`) fly the follower
relative to the leader, so the two vehicles' velocities there are nearly always alike; a model
trained on them cannot tell the leader's velocity (which skews its wake) from the follower's.
These flights give it the real task's geometry. What differs from the real flights: both
vehicles fly the world's position controllers (the nominal one, with the bias observer), not the
firmware's; ``goTo``'s segment is the firmware's planner's polynomial (:func:`goto_profile`). And
the real swaps flew with the Neural-Swarm learnt interaction compensation on (the script sets
``ctrlFa/enableNN`` to 2 for every swap; the data folders' ``readme.txt``: "NN enabled"); these
compensate nothing.
"""

from __future__ import annotations

import numpy as np

from aerodock.config import Config
from aerodock.control.controller import PositionController, Reference
from aerodock.downwash import build_field
from aerodock.flightlog import FlightLog
from aerodock.mission.params import vehicle_meta
from aerodock.mission.recorder import FlightRecorder
from aerodock.mission.settle import settle
from aerodock.rng import TrialRNG
from aerodock.world import World

SWAP_RADIUS_M = 0.25
"""The circle's radius, m (``Radius = 0.25`` in the script)."""
SWAP_TIMES_S = (4.0, 3.0, 2.0)
"""Each swap's duration, s, each flown there and back (``SwapTimes``)."""
PAUSE_S = 0.1
"""The pause after each swap, s (``timeHelper.sleep(swapTime + 0.1)``)."""
SWAP_SEPARATIONS_M: dict[tuple[str, str], tuple[float, float]] = {
    ("small", "small"): (0.2, 0.4),
    ("small", "large"): (0.4, 0.6),
    ("large", "small"): (0.1, 0.3),
    ("large", "large"): (0.2, 0.4),
}
"""(lower vehicle, upper vehicle) -> the range of the upper one's height above the lower one, m,
drawn uniformly per flight (the script's ``Heights``; a Crazyflie's id below 100: small)."""


def goto_profile(tau: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The fraction of a ``goTo`` flown at normalised time ``tau`` (clipped to 0..1), and its
    first and second derivatives in ``tau``: the firmware planner's rest-to-rest segment
    (crazyflie-firmware ``pptraj.c``, ``piecewise_plan_7th_order_no_jerk``: a 7th-order
    polynomial with zero velocity, acceleration and jerk at both ends),
    ``s = 35 tau^4 - 84 tau^5 + 70 tau^6 - 20 tau^7``."""
    x = np.clip(np.asarray(tau, dtype=float), 0.0, 1.0)
    x2, x3 = x * x, x * x * x
    s = x3 * x * (35.0 + x * (-84.0 + x * (70.0 - 20.0 * x)))
    ds = x3 * (140.0 + x * (-420.0 + x * (420.0 - 140.0 * x)))
    dds = x2 * (420.0 + x * (-1680.0 + x * (2100.0 - 840.0 * x)))
    return s, ds, dds


def swap_schedule(times_s: tuple[float, ...] = SWAP_TIMES_S,
                  pause_s: float = PAUSE_S) -> list[tuple[float, float, bool]]:
    """The task's segments as ``(start_s, duration_s, outbound)``: each swap time there
    (``outbound``) and back, each followed by the pause."""
    out, t = [], 0.0
    for duration in times_s:
        for outbound in (True, False):
            out.append((t, float(duration), outbound))
            t += duration + pause_s
    return out


def swap_reference(t_s: float, home: np.ndarray, away: np.ndarray,
                   schedule: list[tuple[float, float, bool]]) -> Reference:
    """Every vehicle's reference at task time ``t_s``: on a segment, its ``goTo`` from ``home``
    to ``away`` (n, 3) or back; between segments, at rest where the last one ended."""
    n = home.shape[0]
    zero_n = np.zeros(n)
    p0, p1, tau, duration = home, home, 0.0, 1.0
    for start, dur, outbound in schedule:
        if t_s < start:
            break
        p0, p1 = (home, away) if outbound else (away, home)
        tau, duration = (t_s - start) / dur, dur
    s, ds, dds = goto_profile(np.array(tau))
    d = p1 - p0
    return Reference(p0 + s * d, (ds / duration) * d, (dds / duration**2) * d, zero_n, zero_n)


def swap_task_flights(cfg: Config, n_flights: int, separation_m: tuple[float, float],
                      seed: int, *, free_air_radius_m: float, radius_m: float = SWAP_RADIUS_M,
                      times_s: tuple[float, ...] = SWAP_TIMES_S, name: str = "swap",
                      first_trial: int = 0) -> list[FlightLog]:
    """Fly ``n_flights`` swap-task flights at once (module docstring) and return their logs.

    Args:
        cfg: the world (its leader the upper vehicle, its follower the lower one); the labels'
            basis is ``curriculum.label_basis``.
        n_flights: flights (one batch).
        separation_m: (low, high) range of the leader's height above the follower, m.
        seed: random seed (each flight its own stream).
        free_air_radius_m: the horizontal distance beyond which a sample is free air for the
            labels' constant bias, recorded in each log's meta.
        radius_m: the circle's radius, m.
        times_s: the swaps' durations, s.
        name: prefix of the flights' names.
        first_trial: index of the first flight's random stream.

    Raises:
        ValueError: no flights, a separation range that is not ``0 < low <= high``, or a radius
            or swap time that is not positive.
    """
    from aerodock.collect.curriculum import bar_out_of_the_way

    lo, hi = (float(v) for v in separation_m)
    if n_flights < 1:
        raise ValueError(f"swap flights: need at least one flight, got {n_flights}")
    if not 0.0 < lo <= hi:
        raise ValueError(f"swap flights: separation range must be 0 < low <= high, got "
                         f"{separation_m}")
    if radius_m <= 0.0 or not times_s or min(times_s) <= 0.0:
        raise ValueError(f"swap flights: radius {radius_m} m and swap times {times_s} s must "
                         "be positive")
    n = int(n_flights)
    cfg = bar_out_of_the_way(cfg, lo)
    rng = TrialRNG(seed, n, first_trial)
    world = World(cfg, n, rng, field=build_field(cfg))
    angles = rng.uniform(0.0, 2 * np.pi, size=(n, 2))  # the leader's, the follower's
    separation = rng.uniform(lo, hi, size=n)
    top = -cfg.mission.leader_altitude_m

    def circle(angle: np.ndarray, z: np.ndarray) -> np.ndarray:
        return np.stack([radius_m * np.cos(angle), radius_m * np.sin(angle), z], axis=1)

    z_lead, z_fol = np.full(n, top), top + separation
    homes = (circle(angles[:, 0], z_lead), circle(angles[:, 1], z_fol))
    aways = (circle(angles[:, 0] + np.pi, z_lead), circle(angles[:, 1] + np.pi, z_fol))
    schedule = swap_schedule(tuple(float(t) for t in times_s))
    lead_ctl = PositionController(cfg, n, use_observer=True, vehicle=cfg.leader)
    fol_ctl = PositionController(cfg, n, use_observer=True, has_accelerometer=True)
    world.reset(homes[0], homes[1])
    settle(world, lead_ctl, fol_ctl, lambda t: swap_reference(t, homes[0], aways[0], schedule),
           lambda t: swap_reference(t, homes[1], aways[1], schedule), cfg.mission.settle_s)
    mass = cfg.vehicle.mass_kg
    recorder = FlightRecorder(cfg.curriculum.label_basis, mass)
    world.observed_accel()
    end_s = schedule[-1][0] + schedule[-1][1] + PAUSE_S
    for k in range(int(round(end_s / world.dt_control_s))):
        t = k * world.dt_control_s
        obs_l, obs_f = world.observe()
        lout = lead_ctl.step(obs_l.p, obs_l.v, obs_l.rpy,
                             swap_reference(t, homes[0], aways[0], schedule))
        ref = swap_reference(t, homes[1], aways[1], schedule)
        accel = world.observed_accel() if fol_ctl.uses_accelerometer else None
        fout = fol_ctl.step(obs_f.p, obs_f.v, obs_f.rpy, ref, None, None, accel)
        recorder.before_step(t, world, obs_l, obs_f, fout, ref.p, np.zeros(n, dtype=np.int8))
        world.advance(lout.command, fout.command)
        recorder.after_step(world)
    return recorder.flightlogs(lambda i: {
        "name": f"{name}-{first_trial + i:03d}", "source": "aerodock-sim", "frame": "NED",
        "label_basis": recorder.label_basis, "leader_mass_kg": cfg.leader.mass_kg,
        "follower_mass_kg": mass, **vehicle_meta(cfg), "free_air_radius_m": free_air_radius_m,
        "task": "swap", "separation_m": float(separation[i]), "seed": seed,
        "cable_length_m": cfg.platform.cable_length_m,
    })
