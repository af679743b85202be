"""Helpers of the node tests: a NumPy-only model and a known flight to replay."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from aerodock.flightlog import FlightLog
from aerodock.geometry import euler_to_rotmat, rotmat_to_quat
from aerodock.learning.features import N_FEATURES, N_OUTPUTS
from aerodock.learning.modelfile import ModelSpec, save_model_dir


def random_model(path: Path, kind: str = "so2", seed: int = 3,
                 hidden: tuple[int, ...] = (64, 64)) -> Path:
    """A model directory with random weights (no PyTorch needed), the default architecture."""
    rng = np.random.default_rng(seed)
    sizes = (N_FEATURES[kind], *hidden, N_OUTPUTS[kind])
    weights = [(rng.normal(0, 1 / np.sqrt(sizes[i]), (sizes[i + 1], sizes[i])),
                rng.normal(0, 0.1, sizes[i + 1])) for i in range(len(sizes) - 1)]
    spec = ModelSpec(kind=kind, layer_sizes=sizes, activation="tanh",
                     in_mean=rng.normal(0, 0.2, sizes[0]), in_std=rng.uniform(0.5, 2, sizes[0]),
                     out_mean=rng.normal(0, 0.5, sizes[-1]),
                     out_std=rng.uniform(0.5, 2, sizes[-1]))
    vehicle = {"mass_kg": 0.7, "rotor_radius_m": 0.0635, "n_rotors": 4}
    return save_model_dir(path, spec, weights, vehicles={"leader": vehicle, "follower": vehicle})


def orbit_log(duration_s: float = 3.0, rate_hz: float = 100.0) -> FlightLog:
    """A follower circling 0.3 m off axis 0.6 m below a slowly moving, tilted leader (NED)."""
    t = np.arange(int(duration_s * rate_hz)) / rate_hz
    n = len(t)
    w = 2.0
    lp = np.stack([0.2 * t, 0.1 * np.sin(t), np.full(n, -2.0)], axis=1)
    lv = np.stack([np.full(n, 0.2), 0.1 * np.cos(t), np.zeros(n)], axis=1)
    fp = lp + np.stack([0.3 * np.cos(w * t), 0.3 * np.sin(w * t), 0.6 + 0.05 * np.sin(t)], 1)
    fv = lv + np.stack([-0.6 * np.sin(w * t), 0.6 * np.cos(w * t), 0.05 * np.cos(t)], 1)
    lq = rotmat_to_quat(euler_to_rotmat(0.05 * np.sin(t), 0.08 * np.cos(t), 0.4 * t))
    fq = rotmat_to_quat(euler_to_rotmat(0.1 * np.sin(w * t), -0.1 * np.cos(w * t), 0.2 * t))
    zeros = np.zeros((n, 3))
    return FlightLog(t_s=t, leader_pos_m=lp, leader_vel_mps=lv, leader_quat=lq,
                     follower_pos_m=fp, follower_vel_mps=fv, follower_quat=fq,
                     follower_cmd_accel_mps2=zeros, follower_thrust_n=np.full(n, 6.9),
                     follower_obs_accel_mps2=zeros, meta={"name": "orbit", "frame": "NED"})
