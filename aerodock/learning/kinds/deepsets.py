"""Kind ``"deepsets"``: Neural-Swarm's heterogeneous deep-sets model, on the leader alone.

Shi et al. (Neural-Swarm, ICRA 2020; Neural-Swarm2, T-RO 2021) learn the interaction force on
robot ``i`` as ``f_i = rho_{type(i)}( sum_{types k} sum_{j of type k} phi_k(x_ij) )``: each
neighbour's relative state goes through ``phi`` of its type, the sum (whatever the number of
neighbours, in any order) through ``rho`` of the robot's own type. Here there is one neighbour,
the leader, so the sum is its one term; the types are continuous, the vehicles' wake scales
(``features.WAKE_SCALE_NAMES``), so ``phi`` takes the leader's type beside its relative state and
``rho`` the follower's own type beside ``phi``'s output (the network layout ``"deepsets"``,
``Kind.layout``). The relative state is ``"so2"``'s invariant ``h``, so the model is
SO(2)-equivariant like ``"so2"``: it predicts ``(f_r, f_a)`` (m/s²) in the frame
``(e_r, a3)``::

    phi input  = ( h (6),  v_hA (m/s),  L_A (m) )          the leader: neighbour and its type
    rho input  = ( phi(...) (latent),  v_hB (m/s),  L_B (m) )        the follower's own type
    f = f_r e_r + f_a a3

``phi`` is the first layer (an activation after it), ``rho`` the remaining ones: with the
default hidden widths (64, 64), ``phi: 8 -> 64`` and ``rho: 64 + 2 -> 64 -> 2``.
"""

from __future__ import annotations

from typing import Any

from aerodock.learning.kinds import so2
from aerodock.learning.kinds.base import Kind, Ops, Scene, Vec


def features(s: Scene, ops: Ops) -> tuple[list[Any], list[Vec]]:
    """``h`` and the leader's type (``phi``'s), then the follower's type (``rho``'s)."""
    h, frame = so2.features(s, ops)
    vh_a, size_a, vh_b, size_b = s.scales
    return [*h, vh_a, size_a, vh_b, size_b], frame


KIND = Kind(
    name="deepsets",
    summary="deepsets (Neural-Swarm's rho(phi(leader, its type), own type); needs the "
            "vehicles' rotors in the logs)",
    feature_names=(*so2.KIND.feature_names, "leader_vh_mps", "leader_size_m",
                   "follower_vh_mps", "follower_size_m"),
    output_names=so2.KIND.output_names,
    # the types: 0.1 m/s of hover induced velocity, 1 cm of size
    scale_floor=(*so2.KIND.scale_floor, 0.1, 0.01, 0.1, 0.01),
    features=features,
    n_wake_scales=4,
    ego_features=2,
    phi_layers=1,
)
