"""What a model kind is: one record, and its feature map written once over any array library.

A kind's feature map is a function ``features(s, ops) -> (z, frame)`` of a :class:`Scene`:
``z`` is the list of its F features and ``frame`` the list of its K output vectors (world
frame, each three components), so that the predicted force is ``f = sum_k c_k frame_k`` for the
network's outputs ``c`` (a torque kind's last K outputs go through the same frame to the torque).
It uses only ``+ - * /``, Python floats and ``ops.sqrt`` on per-sample scalars, so the one
definition runs on

* NumPy arrays (n,): the batched runtime, training's features (``features.feature_map``);
* torch tensors (n,): training and the torch module (``features.feature_map_torch``);
* Python floats: the runtime's one-sample hot path (``runtime.Predictor.predict_one``);
* symbolic ONNX tensors: the exported graph (``export``), whose operators add graph nodes.

A kind with ``world_frame`` (the MLP baseline) has no feature map: its features are ``x``
itself and its outputs the world force. The zero model has neither features nor a network.
This module imports nothing but the standard library (the config reads the registry).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

GRAVITY_MPS2 = 9.81
# Lower bounds on the standard deviations used to standardise each feature (in the feature's
# units). A feature that barely varies in the training data (the leader always hovering: |v_A| of
# a few mm/s) must not be blown up to hundreds of standard deviations when it does vary in use.
POS_FLOOR_M, VEL_FLOOR_MPS, ANGLE_FLOOR = 0.05, 0.05, 0.1

Vec = tuple[Any, Any, Any]
"""A world vector as its three components, each a per-sample scalar of the array library."""


class Ops(Protocol):
    """The one operation a feature map needs beyond arithmetic (each array library's own)."""

    def sqrt(self, a: Any) -> Any:
        """Element-wise square root."""


class Scene:
    """What a feature map reads, per sample, as scalars of one array library.

    Attributes:
        px, py, pz: ``dp = p_B - p_A`` in the leader's body coordinates ``R_A^T dp`` (m).
        ax, ay, az: the leader's velocity ``v_A`` in its body coordinates (m/s).
        bx, by, bz: the follower's velocity ``v_B`` in the leader's body coordinates (m/s).
        a1, a2, a3: the leader's body axes in world coordinates (the columns of ``R_A``).
        scales: the wake scales' columns the kind reads (``features.WAKE_SCALE_NAMES``).
        eps_p2, eps_v2: the squared regularisation constants ``EPS_POS_M**2`` (m^2) and
            ``EPS_VEL_MPS**2`` (m^2/s^2).
    """

    __slots__ = ("a1", "a2", "a3", "ax", "ay", "az", "bx", "by", "bz", "eps_p2", "eps_v2",
                 "px", "py", "pz", "scales")

    def __init__(self, body: Sequence[Any], axes: Sequence[Vec], scales: Sequence[Any],
                 eps_p2: float, eps_v2: float) -> None:
        """``body``: the nine body components ``(px, py, pz, ax, ay, az, bx, by, bz)``;
        ``axes``: ``(a1, a2, a3)``; ``scales``: the wake scales' columns."""
        (self.px, self.py, self.pz, self.ax, self.ay, self.az,
         self.bx, self.by, self.bz) = body
        self.a1, self.a2, self.a3 = axes
        self.scales = scales
        self.eps_p2, self.eps_v2 = eps_p2, eps_v2


FeatureMap = Callable[[Scene, Ops], tuple[list[Any], list[Vec]]]


@dataclass(frozen=True)
class Kind:
    """One model kind: everything the pipeline knows of it.

    Attributes:
        name: the kind's name (model files, configs, the command line).
        summary: one line for the command line's help.
        feature_names: the F features' names (``model.json`` -> ``features.names``).
        output_names: the network's outputs' names (``model.json`` -> ``outputs``).
        scale_floor: per feature, the least standard deviation it is standardised with.
        features: the feature map (see the module docstring); None for ``world_frame`` kinds
            and the zero model.
        world_frame: the features are ``x`` itself and the outputs the world force.
        scale_groups: features standardised with one shared scale (indices).
        n_wake_scales: how many wake scales (the first ones) it takes as a third input.
        torque: it also predicts the wake's torque (outputs: the force's K, then the torque's).
        scaled_frame: the frame's vectors carry a force scale (the last vector's squared length
            divides the training targets, see ``features.invariant_components``).
        equivariant: rotating the scene about the leader's axis rotates its prediction.
        has_network: False for the zero model only.
        ego_features: 0 for a plain network; for a deep-sets network (:attr:`layout`), how many
            of the last features are the follower's own (they enter ``rho``, the rest ``phi``).
        phi_layers: a deep-sets network's layers that belong to ``phi`` (the first ones).
    """

    name: str
    summary: str
    feature_names: tuple[str, ...] = ()
    output_names: tuple[str, ...] = ()
    scale_floor: tuple[float, ...] = ()
    features: FeatureMap | None = None
    world_frame: bool = False
    scale_groups: tuple[tuple[int, ...], ...] = ()
    n_wake_scales: int = 0
    torque: bool = False
    scaled_frame: bool = False
    equivariant: bool = True
    has_network: bool = True
    ego_features: int = 0
    phi_layers: int = 1

    def __post_init__(self) -> None:
        if len(self.scale_floor) != len(self.feature_names):
            raise ValueError(f"kind {self.name!r}: one scale floor per feature")
        if self.has_network and self.features is None and not self.world_frame:
            raise ValueError(f"kind {self.name!r}: a network needs a feature map")
        if not 0 <= self.ego_features < max(self.n_features, 1) or self.phi_layers < 1:
            raise ValueError(f"kind {self.name!r}: ego_features or phi_layers out of range")

    @property
    def layout(self) -> str:
        """The network: ``"mlp"``, one stack of layers ``[F, hidden..., K]``; ``"deepsets"``,
        Neural-Swarm's ``rho(sum_j phi(z_j), z_ego)``: the first :attr:`phi_layers` layers are
        ``phi`` (on the neighbour's features, an activation after each), their output (one
        neighbour: the sum is itself) and the :attr:`ego_features` enter ``rho``, the rest;
        ``"none"``, the zero model."""
        if not self.has_network:
            return "none"
        return "deepsets" if self.ego_features else "mlp"

    def weight_shapes(self, layer_sizes: Sequence[int]
                      ) -> list[tuple[tuple[int, int], tuple[int]]]:
        """``(W shape, b shape)`` per layer for layer sizes ``[F, hidden..., K]`` (torch's
        ``Linear`` layout): a chain, except in a deep-sets network, whose first layer takes the
        neighbour's ``F - ego`` features and whose first ``rho`` layer the ego features too.

        Raises:
            ValueError: a deep-sets network with no layer for ``rho``.
        """
        s, e = [int(v) for v in layer_sizes], self.ego_features
        if e and len(s) - 1 <= self.phi_layers:
            raise ValueError(f"kind {self.name!r} needs more than {self.phi_layers} hidden "
                             "layers (phi's, then rho's)")
        return [((s[i + 1], s[i] - (e if i == 0 else 0) + (e if e and i == self.phi_layers
                                                           else 0)), (s[i + 1],))
                for i in range(len(s) - 1)]

    @property
    def n_features(self) -> int:
        """F, the number of features."""
        return len(self.feature_names)

    @property
    def n_outputs(self) -> int:
        """The number of network outputs (K, or 2K for a torque kind)."""
        return len(self.output_names)



def scaled(v: Vec, s: Any) -> Vec:
    """``v * s`` for a world vector and a per-sample scalar."""
    return (v[0] * s, v[1] * s, v[2] * s)


def combined(v: Vec, s: Any, w: Vec, t: Any) -> Vec:
    """``v * s + w * t`` for world vectors ``v``, ``w`` and per-sample scalars ``s``, ``t``."""
    return (v[0] * s + w[0] * t, v[1] * s + w[1] * t, v[2] * s + w[2] * t)


class Planar:
    """The quantities every SO(2) kind shares (``features`` module docstring), computed once.

    Attributes:
        rho2, rho: ``|proj dp|^2`` and ``|proj dp|``.
        urx, ury: the soft radial unit vector ``proj dp / sqrt(rho^2 + eps^2)`` in ``(a1, a2)``.
        vb2, va2: ``|proj v_B|^2``, ``|proj v_A|^2``.
        vb_soft: ``sqrt(|proj v_B|^2 + eps_v^2)``.
        cos_b: the soft cosine of the angle from ``proj dp`` to ``proj v_B``.
        e_r: the radial vector ``a1 urx + a2 ury`` (world, length ``s(rho)``).
    """

    __slots__ = ("cos_b", "e_r", "rho", "rho2", "urx", "ury", "va2", "vb2", "vb_soft")

    def __init__(self, s: Scene, ops: Ops) -> None:
        """The shared quantities of scene ``s``."""
        self.rho2 = rho2 = s.px * s.px + s.py * s.py
        self.rho = ops.sqrt(rho2)
        rho_soft = ops.sqrt(rho2 + s.eps_p2)
        self.urx = urx = s.px / rho_soft
        self.ury = ury = s.py / rho_soft
        self.vb2 = vb2 = s.bx * s.bx + s.by * s.by
        self.va2 = s.ax * s.ax + s.ay * s.ay
        self.vb_soft = vb_soft = ops.sqrt(vb2 + s.eps_v2)
        self.cos_b = (urx * s.bx + ury * s.by) / vb_soft
        self.e_r = combined(s.a1, urx, s.a2, ury)


def signed_features(s: Scene, p: Planar, ops: Ops) -> tuple[list[Any], list[Vec]]:
    """The ten signed invariant features and the frame ``(e_r, e_t, a3)`` of ``"so2-ext"`` (and
    ``"so2-wrench"``): ``(cos_B, sin_B, |proj dp|, |proj v_B|, a3 . dp, a3 . v_B, |proj v_A|,
    cos_A, sin_A, a3 . v_A)``."""
    va_soft = ops.sqrt(p.va2 + s.eps_v2)
    sin_b = (p.urx * s.by - p.ury * s.bx) / p.vb_soft
    cos_a = (p.urx * s.ax + p.ury * s.ay) / va_soft
    sin_a = (p.urx * s.ay - p.ury * s.ax) / va_soft
    z = [p.cos_b, sin_b, p.rho, ops.sqrt(p.vb2), s.pz, s.bz, ops.sqrt(p.va2), cos_a, sin_a, s.az]
    a1, a2 = s.a1, s.a2  # the tangential vector e_t = a2 urx - a1 ury
    e_t = (a2[0] * p.urx - a1[0] * p.ury, a2[1] * p.urx - a1[1] * p.ury,
           a2[2] * p.urx - a1[2] * p.ury)
    return z, [p.e_r, e_t, s.a3]
