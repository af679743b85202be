"""Synthetic two-vehicle flights made by the simulator's wake (the default jet, stepped at the
physics rate with its own turbulence), logged at 100 Hz as real logs are: the follower passes
under a hovering leader at several depths and offsets and spends time in free air; its label
carries white noise and a constant per-flight bias, as the Neural-Swarm residuals do."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from jets import default_jet

from aerodock.downwash.base import BodyState
from aerodock.flightlog import FlightLog
from aerodock.geometry import GRAVITY_MPS2, quat_to_rotmat, rotmat_to_quat
from aerodock.identify.flights import log_geometry
from aerodock.identify.wake_fit import build_jet
from aerodock.identify.wake_torque import BODY_RATES_KEY, MOTOR_TORQUE_KEY

# Crazyflie-like vehicles: mass, rotor radius, diagonal.
SMALL = (0.032, 0.0225, 0.092)
LARGE = (0.067, 0.024, 0.120)
PAIRS = {"ss": (SMALL, SMALL), "sl": (LARGE, SMALL), "ls": (SMALL, LARGE)}  # (leader, follower)


def pass_path(depths_m, t_pass_s: float, rate_hz: float, rng: np.random.Generator,
              reach_m: float) -> np.ndarray:
    """Follower offsets (T, 3) from the leader: straight passes under it at each depth, each
    with a random heading and a small lateral miss, then a stretch in free air."""
    out = []
    for depth in depths_m:
        n = int(t_pass_s * rate_hz)
        heading = rng.uniform(0, 2 * np.pi)
        miss = rng.uniform(-0.5, 0.5) * reach_m / 4
        s = np.linspace(-reach_m, reach_m, n)
        d = np.array([np.cos(heading), np.sin(heading)])
        perp = np.array([-d[1], d[0]])
        xy = s[:, None] * d + miss * perp
        out.append(np.column_stack([xy, np.full(n, depth)]))
        far = int(1.0 * rate_hz)  # a second in free air, beside the leader
        out.append(np.column_stack([np.full(far, 3.0), np.zeros(far), np.full(far, depth)]))
    return np.concatenate(out)


class _Streams:
    """One random stream per flight, for a field that flies several flights as one batch: a
    draw of shape ``(n, k)`` takes row ``i`` from flight ``i``'s own generator, in the order that
    flight alone would draw it (so each flight's numbers are those of flying it alone)."""

    def __init__(self, gens: list[np.random.Generator]):
        self.gens = gens

    def standard_normal(self, size) -> np.ndarray:
        n, *rest = size
        assert n == len(self.gens), size
        return np.stack([g.standard_normal(tuple(rest)) for g in self.gens])


def synthetic_pair(pair: str, flights: list[int], params: dict, *, seeds: list[int], depths_m,
                   noise_mps2: float = 0.15, t_pass_s: float = 3.0) -> list[FlightLog]:
    """Flights of ``pair`` ("ss", "sl", "ls") in the wake of a jet with ``params``: flight
    ``flights[i]`` draws from ``default_rng(seeds[i])`` alone (its path, its turbulence, its
    bias and noise), the wake stepped for all of them at once."""
    (m_l, r_l, d_l), (m_f, r_f, d_f) = PAIRS[pair]
    gens = [np.random.default_rng(seed) for seed in seeds]
    rate, substeps = 100.0, 5
    dt = 1.0 / (rate * substeps)
    field = default_jet(**params, leader_rotor_radius_m=r_l, follower_rotor_radius_m=r_f,
                          follower_diagonal_m=d_f)
    offsets = np.stack([pass_path(depths_m, t_pass_s, rate, rng, reach_m=0.25) for rng in gens],
                       axis=1)  # (T, flights, 3)
    n, b = offsets.shape[:2]
    speed = np.gradient(offsets, 1.0 / rate, axis=0)
    eye = np.repeat(np.eye(3)[None], b, axis=0)
    leader = BodyState(np.zeros((b, 3)), np.zeros((b, 3)), eye, np.full(b, m_l * GRAVITY_MPS2),
                       np.full(b, m_l))
    field.reset(b, _Streams(gens))
    accel = np.empty((n, b, 3))
    for i in range(n):
        follower = BodyState(offsets[i], speed[i], eye, np.full(b, m_f * GRAVITY_MPS2),
                             np.full(b, m_f))
        # what an accelerometer logs: the mean over the logging period
        accel[i] = np.mean([field.acceleration(leader, follower, dt) for _ in range(substeps)],
                           axis=0)
    quat = np.tile(rotmat_to_quat(np.eye(3)), (n, 1))
    ids = {"ss": ("cf1", "cf2"), "sl": ("cf9", "cf2"), "ls": ("cf1", "cf9")}[pair]
    logs = []
    for j, (flight, rng) in enumerate(zip(flights, gens, strict=True)):
        bias = rng.normal(0.0, 0.3, 3)
        obs = accel[:, j] + bias + rng.normal(0.0, noise_mps2, (n, 3))
        name = f"synth_{pair}_{flight:02d}"
        logs.append(FlightLog(
            t_s=np.arange(n) / rate, leader_pos_m=np.zeros((n, 3)),
            leader_vel_mps=np.zeros((n, 3)), leader_quat=quat, follower_pos_m=offsets[:, j],
            follower_vel_mps=speed[:, j], follower_quat=quat,
            follower_cmd_accel_mps2=np.zeros((n, 3)),
            follower_thrust_n=np.full(n, m_f * GRAVITY_MPS2), follower_obs_accel_mps2=obs,
            meta={"name": f"{name}_{ids[1]}", "source": "synthetic", "frame": "NED",
                  "label_basis": "command", "leader_mass_kg": m_l, "follower_mass_kg": m_f,
                  "leader_rotor_radius_m": r_l, "follower_rotor_radius_m": r_f,
                  "leader_n_rotors": 4, "follower_n_rotors": 4, "leader_diagonal_m": d_l,
                  "follower_diagonal_m": d_f, "leader_id": ids[0], "follower_id": ids[1]},
            extra={"leader_thrust_n": np.full(n, m_l * GRAVITY_MPS2)},
        ))
    return logs


def synthetic_flight(pair: str, flight: int, params: dict, *, seed: int, depths_m,
                     noise_mps2: float = 0.15, t_pass_s: float = 3.0) -> FlightLog:
    """One flight of ``pair`` ("ss", "sl", "ls") in the wake of a jet with ``params``."""
    return synthetic_pair(pair, [flight], params, seeds=[seed], depths_m=depths_m,
                          noise_mps2=noise_mps2, t_pass_s=t_pass_s)[0]


def synthetic_flights(params: dict, flights_per_pair: int = 4, seed: int = 0) -> list[FlightLog]:
    """Flights of all three pairs at Crazyflie-like depths (small leader 0.15-0.45 m, large
    leader 0.4-0.6 m); each pair's flights fly as one batch, each with its own random stream."""
    depths = {"ss": (0.2, 0.3, 0.4), "sl": (0.15, 0.25, 0.35), "ls": (0.4, 0.5, 0.6)}
    logs = []
    for k, pair in enumerate(PAIRS):
        flights = list(range(flights_per_pair))
        logs += synthetic_pair(pair, flights, params, seeds=[seed + 100 * k + j for j in flights],
                               depths_m=depths[pair])
    return logs


def answering_motors(log: FlightLog, params: dict, gain: float, trim: np.ndarray,
               rng: np.random.Generator) -> FlightLog:
    """``log`` with motors that hold the follower level against ``gain`` times the jet's mean
    disk torque (their torque: the trim minus it, plus noise) and no rotation."""
    n = log.n_samples
    geometry = log_geometry(log)
    jet = build_jet(params, geometry)
    m_l, m_f = geometry["leader_mass_kg"], geometry["follower_mass_kg"]
    leader = BodyState(log.leader_pos_m, log.leader_vel_mps, quat_to_rotmat(log.leader_quat),
                       np.full(n, m_l * GRAVITY_MPS2), np.full(n, m_l))
    follower = BodyState(log.follower_pos_m, log.follower_vel_mps,
                         quat_to_rotmat(log.follower_quat), np.full(n, m_f * GRAVITY_MPS2),
                         np.full(n, m_f))
    torque = jet.mean_disk_torque_nm(leader, follower)
    motors = trim - gain * torque + rng.normal(0.0, 2e-5, (n, 3))
    extra = {**log.extra, MOTOR_TORQUE_KEY: motors, BODY_RATES_KEY: np.zeros((n, 3))}
    return replace(log, extra=extra)
