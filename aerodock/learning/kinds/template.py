"""A template for a new model kind (copy it to ``kinds/<name>.py``; it is not registered).

A kind is one module holding one :class:`~aerodock.learning.kinds.base.Kind` record named
``KIND``; adding its module's name to ``_MODULES`` in ``kinds/__init__.py`` is the one other line
to write: training, the NumPy runtime (batched and one-sample), the ONNX export, model files, the
config's ``curriculum.model`` and the command line's ``--model`` then know it, and
``tests/learning/test_kinds_registry.py`` checks that its NumPy, torch and ONNX predictions agree
and that it is SO(2)-equivariant if its record says so.

The feature map is written once, for every array library: use only ``+ - * /``, Python floats
and ``ops.sqrt`` on the per-sample scalars of the :class:`~aerodock.learning.kinds.base.Scene`
(no ``if`` on values, no NumPy or torch calls). It returns the F features and the K frame vectors
(world, three components each); the prediction is ``f = sum_k c_k frame_k``. Features built only
from invariants (``Planar``'s quantities, the axial components ``pz``, ``bz``, ``az``, the wake
scales) and a frame built from ``e_r``, ``e_t`` and ``a3`` make the kind equivariant.

Keep ``FEATURE_VERSION`` (``features.py``) for changes to existing kinds' features; a new kind
needs none. This example: ``"so2"`` without the leader's velocity (five features).
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
    """Five invariant features and the frame ``(e_r, a3)``."""
    p = Planar(s, ops)
    return [p.cos_b, p.rho, ops.sqrt(p.vb2), s.pz, s.bz], [p.e_r, s.a3]


KIND = Kind(
    name="example",
    summary="example (so2 without the leader's velocity)",  # the command line's help
    feature_names=("cos_dp_vB", "rho_dp_m", "rho_vB_mps", "axial_dp_m", "axial_vB_mps"),
    output_names=("f_radial_mps2", "f_axial_mps2"),  # one per frame vector
    scale_floor=(ANGLE_FLOOR, POS_FLOOR_M, VEL_FLOOR_MPS, POS_FLOOR_M, VEL_FLOOR_MPS),
    features=features,
    # n_wake_scales=4,   # takes the wake scales (features.WAKE_SCALE_NAMES) as s.scales
    # torque=True,       # also the torque: output_names the force's K, then the torque's K
    # equivariant=False, # says it is not SO(2)-equivariant (the tests then check it is not)
)
