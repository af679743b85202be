"""A follower's rotor footprint: carrying a model trained on one follower to a larger one.

A follower feels the leader's wake where its rotors are, not at its centre: its force is the
wake's point field ``f`` averaged over its rotor disks, which sit on a ring of radius ``a``
(half its motor-to-motor diagonal) about its centre. A model trained on one follower has learnt
that average at the training follower's ring, ``F_t = ring_{a_t}[f]``; it has not learnt ``f``.

To second order in the ring's radius (a Taylor expansion of ``f`` about the centre), averaging
over a horizontal ring of radius ``a`` is ``f + (a^2 / 4) lap_h f`` (``lap_h`` the horizontal
Laplacian, ``d2/dx2 + d2/dy2``): the squared radii add when two rings are composed. So a follower
with the larger ring ``a_B`` feels about the trained model's prediction averaged once more, over a
ring of radius::

    c = sqrt(a_B^2 - a_t^2)           (a_B > a_t; zero otherwise)

:func:`footprint_average` does that; nothing is fitted: both radii are the vehicles' published
diagonals (``{role}_diagonal_m`` in the flights' metadata and ``model.json``'s ``vehicles``).
Left out: each disk's own area, which adds ``r^2 / 8 lap_h f`` for a rotor of radius ``r`` (so
``c^2`` would gain ``(r_B^2 - r_t^2) / 2``: 0.0385 m becomes about 0.042 m from the small to the
large Crazyflie, with the radii ``aerodock ingest`` records), and the validity of the expansion
itself, which needs ``c`` small against the wake's width (a Crazyflie's wake is about 0.07 m
wide at the flights' depths): the footprint is applied only where a caller asks for it.

It carries the force only: the torque of a ``"so2-wrench"`` model (``predict_wrench``,
``predict_torque``) is predicted as trained. A kind that already reads the follower's size
(``"so2-pair"``, ``"deepsets"``) gets the footprint on top of what it learnt of sizes.
A smaller follower than the trained one would need the average undone (a deconvolution, which
amplifies the model's error): it is left as the model predicts, and :func:`footprint_radius_m`
returns zero for it. The ring is sampled at :data:`RING_POINTS` points (the training flights
do not say how the rotors stood in yaw, so their four points become a ring), in the world's
horizontal plane (the follower flies nearly level where the wake matters).

``docs/results/size-transfer.md`` measures it: a model trained on the small Crazyflie pair,
judged on a large Crazyflie's real flights under a small leader.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

RING_POINTS = 8
"""Points on the footprint's ring (evenly spaced, half a step off the x axis)."""


def footprint_radius_m(trained_diagonal_m: float | np.ndarray | None,
                       follower_diagonal_m: float | np.ndarray | None) -> np.ndarray:
    """The extra ring's radius ``sqrt(a_B^2 - a_t^2)`` (m), ``a = diagonal / 2``; zero where
    the follower is not larger than the trained one or either diagonal is unknown (None, NaN or
    not positive). Broadcasts over arrays."""
    if trained_diagonal_m is None or follower_diagonal_m is None:
        return np.zeros(np.shape(follower_diagonal_m))
    if isinstance(trained_diagonal_m, bool | str) or isinstance(follower_diagonal_m, bool | str):
        raise ValueError("a diagonal must be a number of metres, not a flag or a string")
    trained = np.asarray(trained_diagonal_m, dtype=float) / 2.0
    flying = np.asarray(follower_diagonal_m, dtype=float) / 2.0
    with np.errstate(invalid="ignore"):
        extra = flying * flying - trained * trained
        known = np.isfinite(extra) & (trained > 0) & (flying > 0) & (extra > 0)
    return np.where(known, np.sqrt(np.where(known, extra, 0.0)), 0.0)


def footprint_average(predict: Callable[..., np.ndarray], x: np.ndarray, leader_R: np.ndarray,
                      radius_m: float | np.ndarray, *per_sample: np.ndarray) -> np.ndarray:
    """``predict(x, leader_R, *per_sample)`` averaged over a horizontal ring of ``radius_m``
    about each follower (``x``'s first three columns, ``dp``, moved by the ring's points;
    velocities, the leader's attitude and ``per_sample`` unchanged). Samples of radius zero are
    ``predict``'s own values, bit for bit.

    Args:
        predict: a batched prediction, ``(n, 9), (n, 3, 3), *(n, ...) -> (n, 3)``.
        x: (n, 9) model inputs ``[dp, v_A, v_B]``.
        leader_R: (n, 3, 3) the leader's attitude.
        radius_m: scalar or (n,), the ring's radius per sample (:func:`footprint_radius_m`).
        per_sample: further (n, ...) inputs of ``predict`` (a leader-aware model's wake scales).
    """
    x = np.asarray(x, dtype=float)
    radius = np.asarray(radius_m, dtype=float)
    if radius.ndim > 1 or (radius.ndim == 1 and radius.shape[0] != x.shape[0]):
        raise ValueError(f"the footprint's radius must be one value or one per sample "
                         f"({x.shape[0]}), got shape {radius.shape}")
    radius = np.broadcast_to(radius, (x.shape[0],))
    ring = radius > 0
    if not ring.any():
        return np.array(predict(x, leader_R, *per_sample), dtype=float)
    out = np.empty((x.shape[0], 3))
    if not ring.all():
        plain = ~ring
        out[plain] = predict(x[plain], leader_R[plain], *[a[plain] for a in per_sample])
    xr, rr, extra = x[ring], leader_R[ring], [a[ring] for a in per_sample]
    total = np.zeros((xr.shape[0], 3))
    for k in range(RING_POINTS):
        angle = 2.0 * np.pi * (k + 0.5) / RING_POINTS
        moved = xr.copy()
        moved[:, 0] += radius[ring] * np.cos(angle)
        moved[:, 1] += radius[ring] * np.sin(angle)
        total += predict(moved, rr, *extra)
    out[ring] = total / RING_POINTS
    return out
