"""The wake's torque on the follower, predicted by a learnt model, for the autopilot.

:func:`feedforward_torque_nm` is what the mission feeds the autopilot with
``control.torque_feedforward = true``: the model's own torque prediction when it has one (a
``so2-wrench`` model, learnt from torque labels: ``predict_torque_bodies``), otherwise the
torque the force model implies at the rotor hubs (:func:`hub_torque_nm`, below).

The wake acts on the rotor disks, not at the centre of mass: off the wake's axis the inner
rotors are pushed down harder than the outer ones, and the difference pitches the vehicle
towards the axis (up to about 0.13 N m at 10 cm off-axis in the default jet, a fifth of the
autopilot's authority). A learnt force model ``f(x)`` maps where the vehicle is to the wake's
acceleration on the whole vehicle; evaluated with the vehicle's centre at each rotor hub it gives
the share that rotor feels, ``m f(x_i) / k``, and the torque about the centre of mass follows::

    tau = sum_i r_i x (R^T m f(x_i) / k)          (body frame, N m)

A uniform field gives no torque (the hubs are symmetric); a gradient does. The autopilot
subtracts ``tau`` from its rate loop's torque (a feed-forward, so its integrator no longer has to
find the wake's torque after the vehicle has already tilted).
"""

from __future__ import annotations

import numpy as np

from aerodock.control.compensation import AccelPredictor
from aerodock.downwash.base import BodyState


def feedforward_torque_nm(predictor: AccelPredictor, leader: BodyState, follower: BodyState,
                          rotor_offsets_body_m: np.ndarray) -> np.ndarray:
    """(n, 3) predicted wake torque on the follower, body frame FRD, N m, for the autopilot.

    The learnt torque (``predictor.predict_torque_bodies``) when the predictor has one
    (``has_torque``: a ``so2-wrench`` model); otherwise the force model sampled at the rotor
    hubs (:func:`hub_torque_nm`).
    """
    if getattr(predictor, "has_torque", False):
        return predictor.predict_torque_bodies(leader, follower)
    return hub_torque_nm(predictor, leader, follower, rotor_offsets_body_m)


def hub_torque_nm(predictor: AccelPredictor, leader: BodyState, follower: BodyState,
                  rotor_offsets_body_m: np.ndarray) -> np.ndarray:
    """(n, 3) predicted wake torque on the follower, body frame FRD, N m.

    Args:
        predictor: the force model (``predict_bodies``, m/s², NED).
        leader, follower: the bodies as the controller sees them (measured).
        rotor_offsets_body_m: (k, 3) rotor hub positions in the body frame.
    """
    offsets = np.asarray(rotor_offsets_body_m, dtype=float)
    k = offsets.shape[0]
    rot = follower.R
    share = follower.mass_kg / k
    torque = np.zeros_like(follower.p)
    for r in offsets:  # k rotors (4): a loop over rotors, not over trials
        hub = follower.p + rot @ r
        accel = predictor.predict_bodies(leader, BodyState(hub, follower.v, rot,
                                                           follower.thrust_n, follower.mass_kg))
        force_body = np.einsum("nji,nj->ni", rot, accel) * share[:, None]
        torque += np.cross(r, force_body)
    return torque
