"""Kind ``"so2-ext"``: the paper's model with signed features and a tangential force.

The paper's unsigned cosine cannot tell on which side of ``proj dp`` the follower's velocity
lies, so a model on ``h`` cannot express a tangential planar force (e.g. the wake skewing sideways
when the follower moves across it). The extension replaces the cosine by the signed pair
(cos, sin) of the angle from ``proj dp`` to ``proj v_B`` and adds the leader's velocity relative
to ``phi`` (the wake trails behind a moving leader)::

    ( cos_B, sin_B, |proj dp|, |proj v_B|, a3 . dp, a3 . v_B,
      |proj v_A|, cos_A, sin_A, a3 . v_A )

with the same regularisation (``sin_B = (proj dp x proj v_B)_3 / (...)``, and likewise for
``v_A``), all invariant under rotations about ``a3``. It predicts ``(f_r, f_t, f_a)``::

    f = s(rho) (f_r (cos phi a1 + sin phi a2) + f_t (-sin phi a1 + cos phi a2)) + f_a a3
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
    signed_features,
)

FEATURE_NAMES = ("cos_dp_vB", "sin_dp_vB", "rho_dp_m", "rho_vB_mps", "axial_dp_m",
                 "axial_vB_mps", "rho_vA_mps", "cos_dp_vA", "sin_dp_vA", "axial_vA_mps")
SCALE_FLOOR = (ANGLE_FLOOR, ANGLE_FLOOR, POS_FLOOR_M, VEL_FLOOR_MPS, POS_FLOOR_M,
               VEL_FLOOR_MPS, VEL_FLOOR_MPS, ANGLE_FLOOR, ANGLE_FLOOR, VEL_FLOOR_MPS)


def features(s: Scene, ops: Ops) -> tuple[list[Any], list[Vec]]:
    """The ten signed features and the frame ``(e_r, e_t, a3)``."""
    return signed_features(s, Planar(s, ops), ops)


KIND = Kind(
    name="so2-ext",
    summary="so2-ext (signed features, a tangential force)",
    feature_names=FEATURE_NAMES,
    output_names=("f_radial_mps2", "f_tangential_mps2", "f_axial_mps2"),
    scale_floor=SCALE_FLOOR,
    features=features,
)
