"""Kind ``"mlp"``: the plain baseline on ``x = [dp, v_A, v_B]`` in the world frame.

Its features are ``x`` itself and its outputs the world force (no feature map). The horizontal
components of each world vector (north, east) share one standardisation scale, so that
standardising keeps a rotation of the scene about the vertical a rotation (a pass flown
north-south looks, to the network, like the same pass flown east-west; with a scale per axis the
axis the training flights hardly moved along is magnified). Not equivariant.
"""

from __future__ import annotations

from aerodock.learning.kinds.base import POS_FLOOR_M, VEL_FLOOR_MPS, Kind

KIND = Kind(
    name="mlp",
    summary="mlp (the plain baseline)",
    feature_names=("dp_n_m", "dp_e_m", "dp_d_m", "vA_n_mps", "vA_e_mps", "vA_d_mps",
                   "vB_n_mps", "vB_e_mps", "vB_d_mps"),
    output_names=("f_n_mps2", "f_e_mps2", "f_d_mps2"),
    scale_floor=(POS_FLOOR_M,) * 3 + (VEL_FLOOR_MPS,) * 6,
    world_frame=True,
    scale_groups=((0, 1), (3, 4), (6, 7)),
    equivariant=False,
)
