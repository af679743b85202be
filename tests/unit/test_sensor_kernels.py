"""The compiled sensing kernels against the NumPy expressions they replaced, to the bit."""

from __future__ import annotations

import numpy as np
import pytest

from aerodock.jit import seal
from aerodock.world.sensor_kernels import mocap_noise_kernel


def _numpy_noisy(p, v, rpy, draw, pos_sd, vel_sd, att_sd):
    """Motion capture's former NumPy noise for one vehicle (sensors.motion_capture's noisy)."""
    n = p.shape[0]
    rpy = rpy.copy()
    if att_sd > 0:
        rpy += att_sd * draw[:3].T
        draw = draw[3:]
    noise_p, noise_v = draw[:3].T, draw[3:].T
    return (np.add(p, pos_sd * noise_p, out=np.empty((n, 3))),
            np.add(v, vel_sd * noise_v, out=np.empty((n, 3))), rpy)


@pytest.mark.parametrize("att_sd", [0.0, 0.0123])
@pytest.mark.parametrize("n", [1, 7, 256])
def test_mocap_noise_kernel_bit_for_bit(n: int, att_sd: float) -> None:
    rng = np.random.default_rng(n + int(att_sd * 1e4))
    k = 9 if att_sd > 0 else 6
    vehicles = []
    for _ in range(2):
        state = rng.normal(scale=rng.uniform(0.1, 50.0), size=(3, n, 3))
        draw = rng.standard_normal((n, k)).T  # a transposed view, as the streams give
        vehicles.append((state[0], state[1][:, ::-1], state[2], draw))
    pos_sd, vel_sd = 10 ** rng.uniform(-4, 0), 10 ** rng.uniform(-4, 0)
    out = np.empty((6, n, 3))
    (lp, lv, lr, ld), (fp, fv, fr, fd) = vehicles
    mocap_noise_kernel(lp, lv, lr, ld, fp, fv, fr, fd, pos_sd, vel_sd, att_sd, out)
    seal(mocap_noise_kernel)
    for o, (p, v, rpy, draw) in zip((0, 3), vehicles, strict=True):
        want = _numpy_noisy(p, v, rpy, draw, pos_sd, vel_sd, att_sd)
        for got, expect in zip(out[o:o + 3], want, strict=True):
            assert got.tobytes() == expect.tobytes()
