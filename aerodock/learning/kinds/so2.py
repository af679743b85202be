"""Kind ``"so2"``: the paper's SO(2)-equivariant model.

Its features are the paper's ``h: R^9 -> R^6`` (equation ``featuremap``)::

    h = ( cos(angle between proj dp and proj v_B),  |proj dp|,  |proj v_B|,
          a3 . dp,  a3 . v_B,  |proj v_A| )

and it predicts ``(f_r, f_a)``, rotated back with the radial vector::

    f = f_r s(rho) (cos phi a1 + sin phi a2) + f_a a3

(regularised as :mod:`aerodock.learning.features` says). With the paper's unsigned cosine a
tangential component has no well-defined sign, so the paper model has none.
"""

from __future__ import annotations

from typing import Any

from aerodock.learning.kinds.base import (
    ANGLE_FLOOR,
    POS_FLOOR_M,
    VEL_FLOOR_MPS,
    Kind,
    Ops,
    Planar,
    Scene,
    Vec,
)


def features(s: Scene, ops: Ops) -> tuple[list[Any], list[Vec]]:
    """``h`` and the frame ``(e_r, a3)``."""
    p = Planar(s, ops)
    return [p.cos_b, p.rho, ops.sqrt(p.vb2), s.pz, s.bz, ops.sqrt(p.va2)], [p.e_r, s.a3]


KIND = Kind(
    name="so2",
    summary="so2 (the paper's)",
    feature_names=("cos_dp_vB", "rho_dp_m", "rho_vB_mps", "axial_dp_m", "axial_vB_mps",
                   "rho_vA_mps"),
    output_names=("f_radial_mps2", "f_axial_mps2"),
    scale_floor=(ANGLE_FLOOR, POS_FLOOR_M, VEL_FLOOR_MPS, POS_FLOOR_M, VEL_FLOOR_MPS,
                 VEL_FLOOR_MPS),
    features=features,
)
