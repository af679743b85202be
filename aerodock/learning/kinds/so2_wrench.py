"""Kind ``"so2-wrench"``: ``"so2-ext"``'s features and frame, and the wake's torque too.

Six outputs, the force's and the torque's components in the frame ``(e_r, e_t, a3)``::

    f   = s(rho) (f_r e_r' + f_t e_t') + f_a a3                (m/s², world NED)
    tau = s(rho) (tau_r e_r' + tau_t e_t') + tau_a a3          (N m, world NED)

(``e_r'``, ``e_t'`` the unit radial and tangential vectors). A torque is an axial vector, but the
symmetry is a rotation about ``a3`` (no reflection), under which it turns like the force: rotating
the scene about the leader's axis rotates both predictions. The wake's torque on a follower off
the axis points along ``+e_t`` (it pushes the rotors nearer the axis down). Labels are measured in
the follower's body frame and rotated to the world frame with its attitude before training.
"""

from __future__ import annotations

from aerodock.learning.kinds import so2_ext
from aerodock.learning.kinds.base import Kind

KIND = Kind(
    name="so2-wrench",
    summary="so2-wrench (force and torque; needs logs with torques)",
    feature_names=so2_ext.FEATURE_NAMES,
    output_names=("f_radial_mps2", "f_tangential_mps2", "f_axial_mps2",
                  "tau_radial_nm", "tau_tangential_nm", "tau_axial_nm"),
    scale_floor=so2_ext.SCALE_FLOOR,
    features=so2_ext.features,
    torque=True,
)
