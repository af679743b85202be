"""PyTorch downwash models: the paper's SO(2) model, its extension, a plain MLP, and zero.

All models map ``x = [dp, v_A, v_B]`` (n, 9) and the leader's attitude ``leader_R`` (n, 3, 3) to
the predicted downwash acceleration on the follower (n, 3), m/s², world NED. A model is::

    z, M = features(x, leader_R)                        # aerodock.learning.features
    c = MLP((z - in_mean) / in_std) * out_std + out_mean   # K invariant components
    f = M @ c                                           # back to the world frame

The kinds (``"so2"``, the paper's; ``"so2-ext"``; ``"so2-wrench"``, force and torque;
``"so2-leader"`` and ``"so2-pair"``, leader-aware; ``"mlp"``, the plain baseline; ``"zero"``)
are the records of :mod:`aerodock.learning.kinds`: one :class:`DownwashModel` class serves every
kind with a network (its features, frame, scale floors and torque flag are the kind's), and
:class:`ZeroModel` the zero model. A torque kind's ``forward`` is the force, as for every kind;
:meth:`DownwashModel.wrench` gives both, and it is trained on standardised outputs
(:func:`standardised_wrench_loss`), so force and torque weigh alike.

Network: fully connected, two hidden layers of 64 by default, **tanh** activations. tanh is smooth
(so is the learnt force, which the LQR feed-forward differentiates through the closed loop) and
bounded: far outside the training data the prediction saturates instead of growing linearly, a
safety property for a model running inside a controller. Optional spectral normalisation of every
layer bounds the network's Lipschitz constant (in standardised units), as in Neural-Lander style
learnt-residual controllers. Input standardisation and output scaling are buffers of the module
and are saved with it.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import torch
from torch import nn

from aerodock.learning.features import EPS_POS_M, EPS_VEL_MPS, feature_map_torch
from aerodock.learning.kinds import get_kind
from aerodock.learning.modelfile import ModelSpec, load_model_dir

DEFAULT_HIDDEN = (64, 64)
DEFAULT_ACTIVATION = "tanh"


def _activation(name: str) -> nn.Module:
    if name == "tanh":
        return nn.Tanh()
    if name == "silu":
        return nn.SiLU()
    raise ValueError(f"unknown activation {name!r} (expected 'tanh' or 'silu')")


class DownwashModel(nn.Module):
    """A model of any kind with a network: features, standardised MLP, output map (see the
    module docstring)."""

    def __init__(
        self,
        hidden: Sequence[int] = DEFAULT_HIDDEN,
        *,
        kind: str = "so2",
        activation: str = DEFAULT_ACTIVATION,
        spectral_norm: bool = False,
        eps_pos_m: float = EPS_POS_M,
        eps_vel_mps: float = EPS_VEL_MPS,
    ) -> None:
        """Build an untrained (randomly initialised) model.

        Args:
            hidden: hidden layer widths.
            kind: a registered kind with a network (:mod:`aerodock.learning.kinds`).
            activation: ``"tanh"`` (default) or ``"silu"``.
            spectral_norm: spectrally normalise every linear layer while training.
            eps_pos_m: feature regularisation (see :mod:`aerodock.learning.features`).
            eps_vel_mps: feature regularisation.
        """
        super().__init__()
        record = get_kind(kind)
        if not record.has_network:
            raise ValueError(f"model kind {kind!r} has no network")
        self.kind = kind
        self.scale_floor = record.scale_floor
        self.scale_groups = record.scale_groups
        self.torque = record.torque
        n_in, n_out = record.n_features, record.n_outputs
        self.layer_sizes = (n_in, *[int(h) for h in hidden], n_out)
        self.activation = activation
        self.spectral_norm = spectral_norm
        self.eps_pos_m = eps_pos_m
        self.eps_vel_mps = eps_vel_mps
        self.act = _activation(activation)
        self.ego_features, self.phi_layers = record.ego_features, record.phi_layers
        linears = []
        for (b, a), _ in record.weight_shapes(self.layer_sizes):
            lin = nn.Linear(a, b)
            if spectral_norm:
                lin = nn.utils.parametrizations.spectral_norm(lin)
            linears.append(lin)
        self.linears = nn.ModuleList(linears)
        self.register_buffer("in_mean", torch.zeros(n_in))
        self.register_buffer("in_std", torch.ones(n_in))
        self.register_buffer("out_mean", torch.zeros(n_out))
        self.register_buffer("out_std", torch.ones(n_out))

    def features(
        self, x: torch.Tensor, leader_R: torch.Tensor, wake_scales: torch.Tensor | None = None
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """Features ``z`` (n, F) and output map ``M`` (n, 3, K) (``wake_scales`` (n, k): the
        leader-aware kinds' third input, see :mod:`aerodock.learning.features`)."""
        return feature_map_torch(
            self.kind, x, leader_R, eps_pos_m=self.eps_pos_m, eps_vel_mps=self.eps_vel_mps,
            wake_scales=wake_scales,
        )

    def components(self, z: torch.Tensor) -> torch.Tensor:
        """Network outputs ``c`` (n, K) for raw features ``z`` (n, F) (a deep-sets kind: the
        ego features join ``phi``'s output before ``rho``'s first layer)."""
        h = (z - self.in_mean) / self.in_std
        e = self.ego_features
        if e:
            h, ego = h[:, :-e], h[:, -e:]
        for i, lin in enumerate(self.linears[:-1]):
            if e and i == self.phi_layers:
                h = torch.cat([h, ego], -1)
            h = self.act(lin(h))
        if e and len(self.linears) - 1 == self.phi_layers:
            h = torch.cat([h, ego], -1)
        return self.linears[-1](h) * self.out_std + self.out_mean

    @property
    def has_torque(self) -> bool:
        """True for a kind that also predicts the wake's torque."""
        return self.torque

    def output_scales(self) -> tuple[float, float]:
        """(force, torque) label scales of a torque kind: the RMS of the standardisation's
        output scales of each (m/s², N m), by which :func:`standardised_wrench_loss` divides
        the errors."""
        std = self.out_std.detach().double()
        k = std.shape[0] // 2
        return (float(torch.sqrt(torch.mean(std[:k] ** 2))),
                float(torch.sqrt(torch.mean(std[k:] ** 2))))

    def head(self, z: torch.Tensor, out_map: torch.Tensor) -> torch.Tensor:
        """World-frame force (n, 3) from precomputed features and output map."""
        return self.wrench_head(z, out_map)[0]

    def wrench_head(self, z: torch.Tensor, out_map: torch.Tensor
                    ) -> tuple[torch.Tensor, torch.Tensor | None]:
        """World-frame force (n, 3), m/s², and torque (n, 3), N m (None for a force-only kind),
        from precomputed features and output map."""
        c = self.components(z)
        k = out_map.shape[-1]
        force = (out_map * c[:, None, :k]).sum(-1)
        if not self.has_torque:
            return force, None
        return force, (out_map * c[:, None, k:]).sum(-1)

    def forward(self, x: torch.Tensor, leader_R: torch.Tensor,
                wake_scales: torch.Tensor | None = None) -> torch.Tensor:
        """Predicted downwash acceleration (n, 3), m/s², NED."""
        return self.head(*self.features(x, leader_R, wake_scales))

    def wrench(self, x: torch.Tensor, leader_R: torch.Tensor,
               wake_scales: torch.Tensor | None = None
               ) -> tuple[torch.Tensor, torch.Tensor | None]:
        """Predicted force (n, 3), m/s², and torque (n, 3), N m, world NED (None without)."""
        return self.wrench_head(*self.features(x, leader_R, wake_scales))

    @torch.no_grad()
    def set_normalisation(self, z: np.ndarray, c: np.ndarray) -> None:
        """Standardisation statistics from training features ``z`` (n, F) and targets ``c`` (n, K).

        Feature scales are floored (the kind's ``scale_floor``) so that a feature that hardly
        varies in training is not magnified when it does vary in use. The features of a group
        of the kind's ``scale_groups`` (the horizontal components of the MLP's world vectors)
        share one scale, the RMS of their standard deviations.
        """
        z = np.asarray(z, dtype=float)
        c = np.asarray(c, dtype=float)
        std = z.std(axis=0)
        for group in self.scale_groups:
            std[list(group)] = np.sqrt(np.mean(std[list(group)] ** 2))
        in_std = np.maximum(std, np.asarray(self.scale_floor))
        out_std = np.maximum(c.std(axis=0), 1e-3)
        for name, val in (("in_mean", z.mean(axis=0)), ("in_std", in_std),
                          ("out_mean", c.mean(axis=0)), ("out_std", out_std)):
            buf = getattr(self, name)
            buf.copy_(torch.as_tensor(val.astype(np.float32), dtype=buf.dtype))

    def spec(self) -> ModelSpec:
        """The :class:`ModelSpec` describing this model (for saving)."""
        return ModelSpec(
            kind=self.kind, layer_sizes=self.layer_sizes, activation=self.activation,
            in_mean=self.in_mean.detach().cpu().double().numpy(),
            in_std=self.in_std.detach().cpu().double().numpy(),
            out_mean=self.out_mean.detach().cpu().double().numpy(),
            out_std=self.out_std.detach().cpu().double().numpy(),
            spectral_norm=self.spectral_norm, eps_pos_m=self.eps_pos_m,
            eps_vel_mps=self.eps_vel_mps,
        )

    @torch.no_grad()
    def weights(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """Effective ``[(W, b), ...]`` as float64 arrays (spectral normalisation applied).

        Call in eval mode: spectral normalisation then uses its stored singular vectors without
        a power-iteration step, so the weights are exactly those the model computes with.
        """
        return [(lin.weight.detach().cpu().double().numpy().copy(),
                 lin.bias.detach().cpu().double().numpy().copy()) for lin in self.linears]


def standardised_wrench_loss(force: torch.Tensor, force_label: torch.Tensor,
                             torque: torch.Tensor, torque_label: torch.Tensor,
                             scales: tuple[float, float]) -> torch.Tensor:
    """Mean of the force's and the torque's mean squared errors, each divided by the square of
    its label scale (``scales`` = (m/s², N m)): force and torque weigh alike, whatever units."""
    force_scale, torque_scale = scales
    return 0.5 * (torch.mean((force - force_label) ** 2) / force_scale**2
                  + torch.mean((torque - torque_label) ** 2) / torque_scale**2)


class ZeroModel(nn.Module):
    """The zero model (no downwash compensation)."""

    kind = "zero"

    has_torque = False

    def forward(self, x: torch.Tensor, leader_R: torch.Tensor,
                wake_scales: torch.Tensor | None = None) -> torch.Tensor:
        """Zeros (n, 3)."""
        return torch.zeros(x.shape[0], 3, dtype=x.dtype, device=x.device)

    def spec(self) -> ModelSpec:
        """The zero model's spec."""
        return ModelSpec(kind="zero")

    def weights(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """No weights."""
        return []


def build_model(
    kind: str,
    *,
    hidden: Sequence[int] = DEFAULT_HIDDEN,
    activation: str = DEFAULT_ACTIVATION,
    spectral_norm: bool = False,
) -> nn.Module:
    """An untrained model of ``kind`` (initialised from torch's global RNG)."""
    if not get_kind(kind).has_network:
        return ZeroModel()
    return DownwashModel(hidden, kind=kind, activation=activation, spectral_norm=spectral_norm)


def model_from_spec(spec: ModelSpec, weights: list[tuple[np.ndarray, np.ndarray]]) -> nn.Module:
    """A torch model (float32, eval mode, no spectral-norm parametrisation) with given weights."""
    if not get_kind(spec.kind).has_network:
        return ZeroModel().eval()
    model = DownwashModel(
        spec.layer_sizes[1:-1], kind=spec.kind, activation=spec.activation, spectral_norm=False,
        eps_pos_m=spec.eps_pos_m, eps_vel_mps=spec.eps_vel_mps,
    )
    model.spectral_norm = spec.spectral_norm
    with torch.no_grad():
        for lin, (w, b) in zip(model.linears, weights, strict=True):
            lin.weight.copy_(torch.as_tensor(w))
            lin.bias.copy_(torch.as_tensor(b))
        for name in ("in_mean", "in_std", "out_mean", "out_std"):
            getattr(model, name).copy_(torch.as_tensor(getattr(spec, name)))
    return model.eval()


def load_torch_model(path: str | Path) -> nn.Module:
    """A model directory as a torch module (float32, eval mode).

    Raises:
        ModelFileError: missing, corrupt or mismatched model files.
    """
    spec, weights, _ = load_model_dir(path)
    return model_from_spec(spec, weights)
