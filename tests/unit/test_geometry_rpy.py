"""rotmat_to_rpy (one compiled call with NumPy's arctan2 and arcsine loops) gives the numbers of the
NumPy code it replaced, to the bit, on rotations and on any matrix (entries past +-1, NaN,
infinities, signed zeros), in any shape and layout."""

from __future__ import annotations

import numpy as np
import pytest

from aerodock.geometry import rotmat_to_rpy, rpy_to_rotmat


def _numpy_rpy(rot: np.ndarray) -> np.ndarray:
    """rotmat_to_rpy as NumPy computed it."""
    rot = np.asarray(rot, dtype=float)
    shape = rot.shape[:-1]
    rot = rot.reshape(-1, 3, 3)
    rpy = np.empty((rot.shape[0], 3))
    np.arctan2(rot[:, 2, 1], rot[:, 2, 2], out=rpy[:, 0])
    sin_pitch = np.minimum(np.maximum(rot[:, 2, 0], -1.0), 1.0)
    np.negative(np.arcsin(sin_pitch, out=sin_pitch), out=rpy[:, 1])
    np.arctan2(rot[:, 1, 0], rot[:, 0, 0], out=rpy[:, 2])
    return rpy.reshape(shape)


def _matrices(rng: np.random.Generator, m: int) -> np.ndarray:
    """Rotations (some near the pitch's +-90 degrees) and a few arbitrary matrices."""
    rpy = rng.uniform(-np.pi, np.pi, (m, 3)) * np.array([1.0, 0.5, 1.0])
    rpy[::7, 1] = np.pi / 2 * rng.choice([-1.0, 1.0]) + rng.normal(0, 1e-9, rpy[::7, 1].shape)
    rot = np.ascontiguousarray(rpy_to_rotmat(rpy))
    odd = rng.random(m) < 0.1
    rot[odd] = rng.normal(size=(int(odd.sum()), 3, 3)) * 1.5
    return rot


@pytest.mark.parametrize("m", [1, 2, 3, 8, 17, 1000])
def test_rotmat_to_rpy_is_numpys(m):
    rng = np.random.default_rng(m)
    for _ in range(5):
        rot = _matrices(rng, m)
        assert rotmat_to_rpy(rot).tobytes() == _numpy_rpy(rot).tobytes()


def test_special_values():
    rng = np.random.default_rng(0)
    rot = _matrices(rng, 12)
    rot[0, 2, 0], rot[1, 2, 0], rot[2, 2, 0], rot[3, 2, 0] = np.nan, 1.0, -1.0, -0.0
    rot[4, 2, 1], rot[4, 2, 2], rot[5, 1, 0], rot[5, 0, 0] = -0.0, -0.0, 0.0, -0.0
    rot[6, 2, 0], rot[7, 2, 0], rot[8, 2, 1], rot[9, 0, 0] = np.inf, -np.inf, np.nan, np.inf
    rot[10, 2, 0], rot[11, 2, 0] = np.nextafter(1.0, 2.0), np.nextafter(-1.0, -2.0)
    with np.errstate(invalid="ignore"):
        want = _numpy_rpy(rot)
        got = rotmat_to_rpy(rot)
    assert got.tobytes() == want.tobytes()


def test_shapes_and_layouts():
    rng = np.random.default_rng(5)
    rot = _matrices(rng, 24)
    cases = [rot[0], rot.reshape(2, 3, 4, 3, 3), rot[::3], np.asfortranarray(rot),
             rot.transpose(0, 2, 1), rot.astype(np.float32), np.round(rot).astype(int)]
    frozen = rot.copy()
    frozen.flags.writeable = False
    cases.append(frozen)
    for case in cases:
        got, want = rotmat_to_rpy(case), _numpy_rpy(case)
        assert got.shape == want.shape
        assert got.tobytes() == want.tobytes()
