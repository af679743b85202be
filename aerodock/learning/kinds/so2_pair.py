"""Kind ``"so2-pair"``: ``"so2-leader"`` with the follower's size in units of the leader's.

A seventh feature, ``L_B / L_A`` (``L_B = sqrt(n_B) R_B``, the fourth wake scale). The force
scale ``a_s`` assumes the follower's rotors take the wake whole; a follower as wide as the wake or
wider does not (it averages the jet over its disks, and part of it falls beside them), and
``L_B / L_A`` is the invariant that says how much. Still invariant: the equivariance holds.
"""

from __future__ import annotations

from typing import Any

from aerodock.learning.kinds import so2_leader
from aerodock.learning.kinds.base import Kind, Ops, Scene, Vec


def features(s: Scene, ops: Ops) -> tuple[list[Any], list[Vec]]:
    """``"so2-leader"``'s features, then ``L_B / L_A``; its frame."""
    z, frame = so2_leader.scaled_features(s, ops)
    return [*z, s.scales[3] / s.scales[1]], frame


KIND = Kind(
    name="so2-pair",
    summary="so2-pair (so2-leader with the follower's size)",
    feature_names=(*so2_leader.FEATURE_NAMES, "follower_size_per_size"),
    output_names=("f_radial_per_scale", "f_axial_per_scale"),
    # the size ratio: 0.1 (a follower a tenth of the leader's size apart)
    scale_floor=(*so2_leader.SCALE_FLOOR, 0.1),
    features=features,
    n_wake_scales=4,
    scaled_frame=True,
)
