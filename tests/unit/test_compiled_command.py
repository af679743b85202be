"""The compiled position command (:mod:`aerodock.control.command_kernel`) gives the numbers its
NumPy implementation gave, to the bit.

``tests/data/numpy_command_3e780c1.npz`` holds what the NumPy ``lqr_command``,
``command_and_applied``, ``accel_to_attitude_thrust`` and ``attitude_thrust_to_accel`` (main at
3e780c1, before the kernels replaced them) returned for :func:`cases`' random inputs: batches of
1, 7 and 300, accelerations that saturate the tilt and the thrust or ask for more than gravity
down, a NaN, per-trial masses, limits and gains. Written by running this file with that code
(``python tests/unit/test_compiled_command.py OUT.npz``). The last bits are the machine's
(SciPy's Riccati solution, NumPy's products): ``numpy_command_3e780c1.KEY.npz`` is that code's
output on the machine ``KEY`` (``tests/numerics_key.py``; 06d0343's version of this module run
with the 3e780c1 tree); a machine with no copy is held to 1e-9 of each array's largest.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from numerics_key import differing, load_golden

from aerodock.control.inversion import (
    accel_to_attitude_thrust,
    attitude_thrust_to_accel,
    command_and_applied,
)
from aerodock.control.lqr import lqr_command, lqr_gain

GOLDEN = Path(__file__).resolve().parents[1] / "data" / "numpy_command_3e780c1.npz"


def cases() -> dict[str, np.ndarray]:
    """Every output for the fixed random inputs, by name."""
    rng = np.random.default_rng(2026)
    k = lqr_gain([1, 1, 8, 0.01, 0.01, 0.1, 1], [0.8, 0.8, 0.8, 1])
    k_t = lqr_gain([30, 30, 400, 2, 2, 6, 1], [0.8, 0.8, 0.8, 1])
    out: dict[str, np.ndarray] = {}
    for n in (1, 7, 300):
        acc = rng.normal(0, 6, (n, 3)) * rng.choice([0.1, 1.0, 3.0], size=(n, 1))
        acc[::3, 2] = rng.normal(12, 3, acc[::3, 2].shape)  # more than gravity down
        if n > 1:
            acc[1] = [np.nan, 0.0, 1.0]
        yaw = rng.normal(0, 3, n)
        mass, t_max = rng.uniform(0.5, 1.0, n), rng.uniform(5.0, 20.0, n)
        for name, value in zip("rpta", command_and_applied(acc, yaw, 0.7, 9.81, 0.61, 13.7),
                               strict=True):
            out[f"applied_{n}_{name}"] = value
        roll, pitch, thrust = accel_to_attitude_thrust(acc, yaw, mass, 9.81, 0.4, t_max)
        out[f"inverse_{n}"] = np.stack([roll, pitch, thrust])
        out[f"forward_{n}"] = attitude_thrust_to_accel(roll, pitch, yaw, thrust, mass, 9.81)
        state = [rng.normal(0, 2, (n, 3)), rng.normal(0, 1, (n, 3)), rng.normal(0, 4, n),
                 rng.normal(0, 2, (n, 3)), rng.normal(0, 1, (n, 3)), rng.normal(0, 1, (n, 3)),
                 rng.normal(0, 4, n), rng.normal(0, 1, n)]
        gains = np.where(rng.random(n)[:, None, None] < 0.5, k_t, k)
        for name, gain in (("shared", k), ("per_trial", gains)):
            accel, rate = lqr_command(gain, *state)
            out[f"lqr_{name}_{n}"] = np.concatenate([accel, rate[:, None]], axis=1)
    return out


def test_the_compiled_command_gives_the_numpy_numbers():
    golden, exact = load_golden(GOLDEN)
    now = cases()
    assert sorted(golden) == sorted(now)
    assert not differing(now, golden, exact)


if __name__ == "__main__":
    np.savez(sys.argv[1], **cases())
