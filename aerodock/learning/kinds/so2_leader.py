"""Kind ``"so2-leader"``: ``"so2"`` made dimensionless with the leader's wake scales.

The paper's ``h`` carries nothing of the leader's thrust or size, so a model on it trained on a
small and a large leader learns their average. This kind takes, besides ``x`` and ``leader_R``,
three **wake scales** per sample (the first three of ``features.WAKE_SCALE_NAMES``, built by
``features.wake_scales`` from the vehicles), all invariant scalars::

    v_hA = sqrt(T_A / (2 rho n_A pi R_A^2))     leader's hover induced velocity, m/s
    L_A  = sqrt(n_A) R_A                        the radius of one disc of the leader's total
                                                rotor area (the wake's width scale), m
    v_hB = sqrt(m_B g / (2 rho n_B pi R_B^2))   follower's hover induced velocity, m/s

and makes the so2 model dimensionless by momentum theory: positions in units of ``L_A``,
velocities in units of ``v_hA``, the force in units of ``a_s = g (v_hA / v_hB)^2``::

    z = ( cos_B, |proj dp| / L_A, |proj v_B| / v_hA, a3 . dp / L_A, a3 . v_B / v_hA,
          |proj v_A| / v_hA )
    f = a_s (c_r s(rho) e_r' + c_a a3)

(``a_s``: a follower of mass ``m_B`` with rotor area ``A_B`` in a wake of speed ``w`` feels about
``rho A_B w^2 / m_B = g (w / v_hB)^2 / 2``, and ``w`` scales with ``v_hA``.) Scales are
invariant, so the equivariance of ``"so2"`` carries over unchanged.
"""

from __future__ import annotations

from typing import Any

from aerodock.learning.kinds.base import (
    ANGLE_FLOOR,
    GRAVITY_MPS2,
    Kind,
    Ops,
    Planar,
    Scene,
    Vec,
    scaled,
)

FEATURE_NAMES = ("cos_dp_vB", "rho_dp_per_size", "rho_vB_per_vh", "axial_dp_per_size",
                 "axial_vB_per_vh", "rho_vA_per_vh")
# dimensionless: 1 leader size (about 5 cm on a Crazyflie), 0.01 v_h (about 4 cm/s)
SCALE_FLOOR = (ANGLE_FLOOR, 1.0, 0.01, 1.0, 0.01, 0.01)


def scaled_features(s: Scene, ops: Ops) -> tuple[list[Any], list[Vec]]:
    """The six dimensionless features and the frame ``(a_s e_r, a_s a3)``."""
    p = Planar(s, ops)
    vh_a, size_a, vh_b = s.scales[0], s.scales[1], s.scales[2]
    ratio = vh_a / vh_b
    accel_scale = ratio * ratio * GRAVITY_MPS2
    z = [p.cos_b, p.rho / size_a, ops.sqrt(p.vb2) / vh_a, s.pz / size_a, s.bz / vh_a,
         ops.sqrt(p.va2) / vh_a]
    return z, [scaled(p.e_r, accel_scale), scaled(s.a3, accel_scale)]


KIND = Kind(
    name="so2-leader",
    summary="so2-leader (leader-aware; needs the vehicles' rotors in the logs)",
    feature_names=FEATURE_NAMES,
    output_names=("f_radial_per_scale", "f_axial_per_scale"),
    scale_floor=SCALE_FLOOR,
    features=scaled_features,
    n_wake_scales=3,
    scaled_frame=True,
)
