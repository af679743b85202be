"""The compiled parts of :mod:`aerodock.geometry`, in a module of their own: the geometry module
is also read by the log readers and the flight node, which load no compiled code (numba), so
:mod:`aerodock.geometry` imports this one on first use."""

from __future__ import annotations

import numpy as np

from aerodock.jit import any_layout, njit, np_arcsin, np_arctan2


@any_layout("rpy")
@njit
def roll_pitch_yaw(loops: np.ndarray, rot: np.ndarray, rpy: np.ndarray) -> None:
    """Of (m, 3, 3) rotations, into (m, 3) ``rpy``: the ZYX roll ``arctan2(R21, R22)``, pitch
    ``-arcsin(clip(R20, -1, 1))`` and yaw ``arctan2(R10, R00)``, each with NumPy's own loop
    (:func:`aerodock.jit.np_arctan2`, :func:`aerodock.jit.np_arcsin`: the C library's differ
    in the last bit), and ``R20`` clipped as ``np.minimum(np.maximum(R20, -1), 1)`` clips it
    (a NaN stays)."""
    np_arctan2(loops, rot[:, 2, 1], rot[:, 2, 2], rpy[:, 0])
    np_arctan2(loops, rot[:, 1, 0], rot[:, 0, 0], rpy[:, 2])
    for i in range(rot.shape[0]):
        s = rot[i, 2, 0]
        s = s if (s >= -1.0 or s != s) else -1.0
        rpy[i, 1] = s if (s <= 1.0 or s != s) else 1.0
    pitch = rpy[:, 1]
    np_arcsin(loops, pitch, pitch)  # in place, as np.arcsin(pitch, out=pitch)
    for i in range(rot.shape[0]):
        pitch[i] = -pitch[i]  # np.negative: the sign bit flipped
