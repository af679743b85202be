"""The moments of the wake's load about the follower's rotor hubs: what the jet, which puts each
disk's force at its hub, leaves out of the disks' torque (docs/crazyflie.md, "The wake's torque
in the logs"; :func:`aerodock.identify.wake_torque.torque_profile` bins them beside the real
torque)."""

from __future__ import annotations

import numpy as np

from aerodock.downwash.base import BodyState
from aerodock.downwash.jet import RoundJetField

# The polar grid on each rotor disk: equal-area rings x azimuths
HUB_RINGS, HUB_AZIMUTHS = 6, 16


def hub_moments_nm(jet: RoundJetField, leader: BodyState, follower: BodyState, *,
                   exponent: float | None = None, rings: int = HUB_RINGS,
                   azimuths: int = HUB_AZIMUTHS) -> np.ndarray:
    """(n, 3) the moments of the jet's mean axial load about the follower's rotor hubs, summed
    over its disks, N·m, body frame (FRD): the part of the disks' torque that the jet, which
    puts each disk's force at its hub (:meth:`RoundJetField.mean_disk_torque_nm`), leaves out.

    A rotor's loss of thrust to an axial inflow ``w`` is, at small inflow, the same per unit of
    disk area (blade-element theory: an element at radius ``r`` loses lift in proportion to
    ``Omega r w``, and the annulus it sweeps grows with ``r``). In the wake's shear each disk's
    load therefore has its centroid off the hub, towards the stronger inflow: for a linear
    inflow across a disk of radius ``R`` the moment is the disk's force times ``R^2 / 4`` times
    the load's relative gradient. Here each point's load is the jet's own ingest law at the
    point, ``phi(w(x) - v) - phi(-v)`` (``w`` its axial wind there, ``v`` the follower's own
    velocity along the axis, ``phi(x) = sign(x) |x|^p`` with the jet's fitted ``p``, or
    ``exponent``: 1 is blade-element theory's load, linear in the inflow; the fitted ``p``,
    0.56, below 1, spreads the load more evenly and gives smaller moments), over an
    equal-area polar grid of ``rings`` x ``azimuths`` points
    on each disk in the follower's body plane; each disk's moment is the jet's axial force on
    it (:meth:`RoundJetField.mean_disk_forces_n`, before any ``disk_torque_gain``) acting at
    the load's centroid, about the hub.
    However the load is spread, a loss of thrust on the disks cannot put the disks'
    torque over their downward force (the lever) beyond the half diagonal plus the rotor
    radius."""
    n = leader.n
    offsets = jet.rotor_offsets_body_m
    k = offsets.shape[0]
    radius = jet.follower_disk_radius_m
    ring = np.sqrt((np.arange(rings) + 0.5) / rings)  # equal areas
    angle = 2.0 * np.pi * (np.arange(azimuths) + 0.5) / azimuths
    grid = np.zeros((rings * azimuths, 3))
    grid[:, 0] = (ring[:, None] * np.cos(angle)[None, :]).ravel() * radius
    grid[:, 1] = (ring[:, None] * np.sin(angle)[None, :]).ravel() * radius
    q = grid.shape[0]
    rot = np.asarray(follower.R, dtype=float)
    at = offsets[:, None, :] + grid[None, :, :]  # (k, q, 3), body
    points = follower.p[:, None, None, :] + np.einsum("nij,kqj->nkqi", rot, at)
    many = k * q

    def repeat(a: np.ndarray) -> np.ndarray:
        return np.repeat(np.asarray(a, dtype=float), many, axis=0)

    around = BodyState(p=repeat(leader.p), v=repeat(leader.v), R=repeat(leader.R),
                       thrust_n=repeat(leader.thrust_n), mass_kg=repeat(leader.mass_kg))
    wind = jet.wind_mps(around, points.reshape(-1, 3)).reshape(n, k, q, 3)
    axis = np.asarray(leader.R, dtype=float)[:, :, 2]  # the wake's axis: the leader's body z
    w = np.einsum("nkqi,ni->nkq", wind, axis)
    v = np.sum(np.asarray(follower.v, dtype=float) * axis, axis=1)[:, None, None]
    p = jet.ingest_exponent if exponent is None else float(exponent)
    load = _phi(w - v, p) - _phi(-v, p)  # (n, k, q)
    total = load.sum(axis=2)
    ok = np.abs(total) > 1e-12 * np.maximum(np.abs(load).sum(axis=2), 1e-300)
    centroid = np.einsum("nkq,qj->nkj", load, grid) / np.where(ok, total, 1.0)[..., None]
    centroid[~ok] = 0.0  # no load to spread
    force = jet.mean_disk_forces_n(leader, follower).T  # (n, k)
    axis_body = np.einsum("nji,nj->ni", rot, axis)
    return np.cross(centroid, force[:, :, None] * axis_body[:, None, :]).sum(axis=1)


def _phi(x: np.ndarray, p: float) -> np.ndarray:
    """The jet's ingest law's ``sign(x) |x|^p``."""
    return np.sign(x) * np.abs(x) ** p
