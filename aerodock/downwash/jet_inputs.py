"""How :class:`~aerodock.downwash.jet.RoundJetField` hands its arguments to the compiled kernels
(:mod:`aerodock.downwash.jet_kernel`): the batch's rows as float arrays (the arrays themselves
when they already are, so the field's caches keyed on read-only arrays keep working), the
leader's arrays, the rotor disks' geometry, and the placeholders for an input a kernel does not
read in a call."""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from aerodock.downwash.base import BodyState
from aerodock.frozen import freeze


def mean_pair_distance_m(offsets_m: np.ndarray) -> float:
    """Mean distance between the rotor-disk centres ``offsets_m`` (k, 3), m (0 for one disk).

    Kept per layout (its values): a wake fit builds a jet per flight at every evaluation of its
    residual, each with the same few layouts."""
    return _mean_pair_distance_m(offsets_m.shape, offsets_m.dtype.str, offsets_m.tobytes())


@lru_cache(maxsize=64)
def _mean_pair_distance_m(shape: tuple[int, ...], dtype: str, values: bytes) -> float:
    offsets_m = np.frombuffer(values, dtype=dtype).reshape(shape)
    k = offsets_m.shape[0]
    if k < 2:
        return 0.0
    diff = offsets_m[:, None, :] - offsets_m[None, :, :]
    dist = np.sqrt((diff * diff).sum(-1))
    return float(dist[np.triu_indices(k, 1)].mean())


# The kernels' placeholders for an input they do not read this call (the processes' is
# writable, as the kernel's argument always is; the draws are read-only, as a TrialRNG's are).
NO_DRAWS = np.zeros((0, 0))
NO_PROCESSES = np.zeros((3, 0))
NO_ROWS = np.zeros((0, 3))
freeze(NO_DRAWS, NO_ROWS)


def rows3(values: np.ndarray) -> np.ndarray:
    """(n, 3) float rows for a kernel (the array itself when it is one)."""
    return np.asarray(values, dtype=float)


def leader_arrays(leader: BodyState) -> tuple[np.ndarray, ...]:
    """The leader's attitude (n, 3, 3), thrust (n,), velocity and position (n, 3)."""
    thrust = np.asarray(leader.thrust_n, dtype=float)
    if thrust.shape != (leader.n,):
        thrust = np.broadcast_to(thrust, (leader.n,))
    return np.asarray(leader.R, dtype=float), thrust, rows3(leader.v), rows3(leader.p)


def offsets_array(rotor_offsets_body_m: np.ndarray) -> np.ndarray:
    """The disks' centres as a (k, 3) float array: the array itself when it is one (the
    geometry's caches are keyed by the object when it is read-only)."""
    offsets = rotor_offsets_body_m
    if (isinstance(offsets, np.ndarray) and offsets.dtype == np.float64 and offsets.ndim == 2
            and offsets.shape[1] == 3):
        return offsets
    return np.asarray(offsets, dtype=float).reshape(-1, 3)
