"""Compiled parts of the world's sensing: motion capture's noise (:func:`mocap_noise_kernel`).

It does elementwise arithmetic only (a product, then a sum: each rounded as NumPy rounds it);
the random draws are made in Python, in the order they always were, and passed in."""

from __future__ import annotations

import numpy as np

from aerodock.jit import any_layout, njit


@any_layout("out")
@njit
def mocap_noise_kernel(lp: np.ndarray, lv: np.ndarray, lrpy: np.ndarray, ldraw: np.ndarray,
                       fp: np.ndarray, fv: np.ndarray, frpy: np.ndarray, fdraw: np.ndarray,
                       pos_sd: float, vel_sd: float, att_sd: float, out: np.ndarray) -> None:
    """Motion capture's observations of the leaders (``l*``) and followers (``f*``): position
    ``p`` (n, 3), velocity ``v`` (n, 3) and angles ``rpy`` (n, 3) plus their noise, into
    ``out`` (6, n, 3): the leaders' p, v, rpy, then the followers'.

    ``*draw`` (k, n): each trial's standard normal draws, component-major; with ``att_sd > 0``
    (k = 9) the angles' three, then the position's and the velocity's; else (k >= 6) the
    position's and the velocity's. Each element is ``x + sd * draw`` (NumPy's
    ``x + sd * noise``: the product rounded, then the sum)."""
    off = 3 if att_sd > 0 else 0
    _noisy(lp, lv, lrpy, ldraw, pos_sd, vel_sd, att_sd, off, out, 0)
    _noisy(fp, fv, frpy, fdraw, pos_sd, vel_sd, att_sd, off, out, 3)


@njit
def _noisy(p: np.ndarray, v: np.ndarray, rpy: np.ndarray, draw: np.ndarray, pos_sd: float,
           vel_sd: float, att_sd: float, off: int, out: np.ndarray, o: int) -> None:
    """One vehicle's rows of :func:`mocap_noise_kernel` into ``out[o:o + 3]``."""
    for i in range(p.shape[0]):
        for j in range(3):
            out[o, i, j] = p[i, j] + pos_sd * draw[off + j, i]
            out[o + 1, i, j] = v[i, j] + vel_sd * draw[off + 3 + j, i]
            if off:
                out[o + 2, i, j] = rpy[i, j] + att_sd * draw[j, i]
            else:
                out[o + 2, i, j] = rpy[i, j]

