"""SO(2)-invariant feature maps (the paper's Eq. ``featuremap``): notation, regularisation, the
wake scales, and the NumPy and torch entry points to every kind's feature map.

Notation (the paper's): the model input is ``x = [dp, v_A, v_B]`` in R^9 with
``dp = p_B - p_A`` (follower minus leader, world NED, m), ``v_A`` and ``v_B`` the leader's and the
follower's velocities (world NED, m/s). ``R_A`` (``leader_R``) maps the leader's body frame to the
world; its columns ``a1, a2, a3`` are the leader's body x, y, z axes in world coordinates
(``a3`` points *down* through the rotor disc for a level leader). ``S_A = span{a1, a2}`` is the
leader's rotor plane. For a world vector ``w``, ``R_A^T w`` are its leader-body coordinates: the
first two are the coordinates of ``proj_S_A(w)`` in the basis ``(a1, a2)``, the third is
``[R^A_E w]_3 = a3 . w``, the component along the leader's axis.

Paper feature map ``h: R^9 -> R^6`` (kind ``"so2"``), in this order::

    h = ( cos(angle between proj dp and proj v_B),  |proj dp|,  |proj v_B|,
          a3 . dp,  a3 . v_B,  |proj v_A| )

and ``phi`` is the angle of ``proj dp`` from ``a1`` in ``S_A``. Writing ``rho = |proj dp|``, the
model predicts invariant components and rotates the planar part back with ``phi``::

    f = f_r * s(rho) (cos phi a1 + sin phi a2) + f_a a3                         ("so2")
    f = s(rho) (f_r (cos phi a1 + sin phi a2) + f_t (-sin phi a1 + cos phi a2)) + f_a a3
                                                                                ("so2-ext")

Degenerate inputs. Two regularisations with small epsilons keep everything finite and smooth and
make the equivariance exact everywhere, including on the leader's axis:

* ``s(rho) = rho / sqrt(rho^2 + EPS_POS_M^2)``: the radial unit vector is computed as
  ``proj dp / sqrt(rho^2 + EPS_POS_M^2)``. Away from the axis (``rho >> 1 mm``) it is the unit
  vector ``(cos phi, sin phi)`` (``s = 0.995`` at 1 cm); on the axis it is 0, so the predicted
  planar force vanishes there, as it must by symmetry (otherwise it would depend on the arbitrary
  choice of ``phi`` at ``proj dp = 0``).
* the cosine is ``proj dp . proj v_B / (sqrt(rho^2 + EPS_POS_M^2) sqrt(|proj v_B|^2 +
  EPS_VEL_MPS^2))``: equal to the paper's cosine to within 1 % once ``rho > 1 cm`` and
  ``|proj v_B| > 0.1 m/s``, and 0 (no preferred direction) when either projection vanishes.
  ``EPS_VEL_MPS = 0.01 m/s`` is the motion-capture velocity noise level, below which the
  direction of ``v_B`` is noise anyway.

``phi`` itself (``phi_rad``) is ``atan2`` of the planar coordinates, defined as 0 on the axis; it
is reported for analysis; the models use the equivalent soft unit vectors above.

Each kind's features and frame are described in its own module of
:mod:`aerodock.learning.kinds` (``so2``, ``so2-ext``, ``so2-wrench``, ``so2-leader``,
``so2-pair``, ``mlp``, ``zero``, ...), one record per kind; the tables of this module
(:data:`KINDS`, :data:`N_FEATURES`, ...) are views of that registry.

A kind's feature map is written once, over a small array interface
(:mod:`aerodock.learning.kinds.base`), and runs on NumPy arrays (the runtime), torch tensors
(training), Python floats (the runtime's one-sample path) and ONNX graph tensors (the export), so
they agree by construction. This module does not import torch at module level.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from aerodock.learning import kinds as _kinds
from aerodock.learning.kinds import REGISTRY, get_kind
from aerodock.learning.kinds.base import GRAVITY_MPS2, Kind, Scene

FEATURE_VERSION = 1
EPS_POS_M = 1e-3
EPS_VEL_MPS = 1e-2

KINDS = _kinds.KINDS
LEADER_KINDS = tuple(name for name, k in REGISTRY.items() if k.n_wake_scales)
"""Kinds that take the wake scales (:data:`WAKE_SCALE_NAMES`) as a third input."""
WAKE_SCALE_NAMES = ("leader_vh_mps", "leader_size_m", "follower_vh_mps", "follower_size_m")
"""The wake scales' columns: the leader's hover induced velocity (m/s), its wake's width scale
``sqrt(n) R`` (m), the follower's hover induced velocity (m/s) and its size ``sqrt(n) R`` (m).
:func:`wake_scales` builds all four; a kind reads the first :data:`N_WAKE_SCALES` of them."""
N_WAKE_SCALES = {name: k.n_wake_scales for name, k in REGISTRY.items() if k.n_wake_scales}
"""How many of the wake scales (the first ones) each leader-aware kind takes."""
AIR_DENSITY_KGPM3 = 1.225
TORQUE_KINDS = tuple(name for name, k in REGISTRY.items() if k.torque)
"""Kinds that also predict the wake's torque (their outputs: force components, then torque's)."""
N_FEATURES = {name: k.n_features for name, k in REGISTRY.items()}
N_OUTPUTS = {name: k.n_outputs for name, k in REGISTRY.items()}
FEATURE_NAMES = {name: k.feature_names for name, k in REGISTRY.items()}
OUTPUT_NAMES = {name: k.output_names for name, k in REGISTRY.items()}
SCALE_FLOOR = {name: k.scale_floor for name, k in REGISTRY.items()}
"""Lower bounds on the standard deviations used to standardise each feature (its units)."""
SCALE_GROUPS = {name: k.scale_groups for name, k in REGISTRY.items() if k.scale_groups}
"""Features standardised with one shared scale (indices into a kind's features)."""


def check_kind(kind: str) -> str:
    """Return ``kind`` if it is a known model kind.

    Raises:
        ValueError: unknown kind.
    """
    return get_kind(kind).name


def _body(w: Any, rot: Any) -> Any:
    """Leader-body coordinates ``R^T w`` of world vectors ``w`` (n, 3), for arrays or tensors."""
    return (rot * w[..., :, None]).sum(-2)


class _PowOps:
    """The array interface of NumPy arrays and torch tensors (``** 0.5`` is their sqrt)."""

    @staticmethod
    def sqrt(a: Any) -> Any:
        return a**0.5


def _array_features(
    kind: Kind, x: Any, rot: Any, stack: Callable[..., Any], eps_pos_m: float, eps_vel_mps: float,
    scales: Any = None,
) -> tuple[Any, Any]:
    """Features ``z`` (n, F) and output map ``M`` (n, 3, K) of a kind's feature map, for
    NumPy arrays or torch tensors (``stack`` the library's).

    The world-frame prediction is ``f = M @ c`` where ``c`` (n, K) are the network's outputs
    (for a torque kind, ``M`` maps the force's K and the torque's K outputs alike).
    """
    body = [_body(x[..., i:i + 3], rot) for i in (0, 3, 6)]
    comps = [b[..., k] for b in body for k in range(3)]
    axes = [(rot[..., 0, k], rot[..., 1, k], rot[..., 2, k]) for k in range(3)]
    cols = [] if scales is None else [scales[..., k] for k in range(kind.n_wake_scales)]
    scene = Scene(comps, axes, cols, eps_pos_m * eps_pos_m, eps_vel_mps * eps_vel_mps)
    z, frame = kind.features(scene, _PowOps)
    return stack(z, -1), stack([stack(v, -1) for v in frame], -1)


EPS_RANGE = (1e-9, 1.0)
"""Accepted range of ``eps_pos_m`` (m) and ``eps_vel_mps`` (m/s): outside it the regularisation
either underflows (``eps**2 == 0``: a division by zero on the leader's axis) or swamps the
features."""


def check_eps(eps_pos_m: float, eps_vel_mps: float) -> None:
    """Validate the feature regularisation constants.

    Raises:
        ValueError: a constant that is not a finite number in :data:`EPS_RANGE`.
    """
    low, high = EPS_RANGE
    for name, value in (("eps_pos_m", eps_pos_m), ("eps_vel_mps", eps_vel_mps)):
        if isinstance(value, bool) or not isinstance(value, int | float | np.floating):
            raise ValueError(f"features.{name} must be a number, got {value!r}")
        if not low <= value <= high:  # also false for NaN
            raise ValueError(f"features.{name} must be between {low:g} and {high:g}, "
                             f"got {value!r}")


def check_inputs(x: np.ndarray, leader_r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Validate model inputs: ``x`` (n, 9) and ``leader_R`` (n, 3, 3), as float arrays."""
    x = np.asarray(x, dtype=float)
    leader_r = np.asarray(leader_r, dtype=float)
    if x.ndim != 2 or x.shape[1] != 9:
        raise ValueError(f"x must have shape (n, 9), got {x.shape}")
    if leader_r.shape != (x.shape[0], 3, 3):
        raise ValueError(f"leader_R must have shape ({x.shape[0]}, 3, 3), got {leader_r.shape}")
    return x, leader_r


def check_wake_scales(wake_scales: Any, n: int, kind: str) -> np.ndarray:
    """Validate wake scales (:data:`WAKE_SCALE_NAMES`) for a leader-aware ``kind``: (n, k) or
    (k,) with ``k`` at least the kind's :data:`N_WAKE_SCALES`, finite and positive.

    Returns:
        (n, N_WAKE_SCALES[kind]): the first columns, the ones the kind reads (more may be given:
        :func:`wake_scales` builds all four, a ``so2-leader`` model takes three).

    Raises:
        ValueError: missing, of the wrong shape, or not finite and positive.
    """
    k = get_kind(kind).n_wake_scales
    names = ", ".join(WAKE_SCALE_NAMES[:k])
    if wake_scales is None:
        raise ValueError(f"a {kind!r} model needs wake_scales (n, {k}): {names}")
    scales = np.asarray(wake_scales, dtype=float)
    if scales.ndim == 1:
        scales = np.broadcast_to(scales, (n, scales.shape[0]))
    if scales.ndim != 2 or scales.shape[0] != n or scales.shape[1] < k:
        raise ValueError(f"wake_scales must have shape ({n}, {k}) ({names}), "
                         f"got {scales.shape}")
    scales = scales[:, :k]
    if not np.all(np.isfinite(scales) & (scales > 0)):
        raise ValueError("wake_scales must be finite and positive")
    return scales


def hover_induced_velocity_mps(thrust_n: Any, rotor_radius_m: Any, n_rotors: Any,
                               air_density_kgpm3: float = AIR_DENSITY_KGPM3) -> np.ndarray:
    """Momentum theory's induced velocity ``sqrt(T / (2 rho n pi R^2))`` (m/s) of a rotorcraft
    producing thrust ``thrust_n`` (N) with ``n_rotors`` rotors of radius ``rotor_radius_m``."""
    area_m2 = np.asarray(n_rotors, float) * np.pi * np.asarray(rotor_radius_m, float) ** 2
    return np.sqrt(np.maximum(np.asarray(thrust_n, float), 0.0)
                   / (2.0 * air_density_kgpm3 * area_m2))


def wake_scales(leader_thrust_n: Any, leader_rotor_radius_m: Any, leader_n_rotors: Any,
                follower_mass_kg: Any, follower_rotor_radius_m: Any, follower_n_rotors: Any,
                *, air_density_kgpm3: float = AIR_DENSITY_KGPM3,
                gravity_mps2: float = GRAVITY_MPS2) -> np.ndarray:
    """The wake scales (n, 4) of the leader-aware kinds (:mod:`aerodock.learning.kinds.so2_leader`).

    Args:
        leader_thrust_n: (n,) or scalar, the leader's collective thrust, N (logged or
            commanded; its hover thrust ``m g`` when neither is known).
        leader_rotor_radius_m, leader_n_rotors: the leader's rotor radius (m) and count.
        follower_mass_kg: the follower's mass, kg (its hover thrust is ``m g``: not its
            instantaneous thrust, which is part of the label).
        follower_rotor_radius_m, follower_n_rotors: the follower's rotors (its size
            ``sqrt(n_B) R_B`` is the fourth scale, read by ``"so2-pair"``).
        air_density_kgpm3: air density, kg/m^3.
        gravity_mps2: gravity, m/s^2.

    Returns:
        ``[v_hA (m/s), sqrt(n_A) R_A (m), v_hB (m/s), sqrt(n_B) R_B (m)]`` per sample.
    """
    thrust = np.atleast_1d(np.asarray(leader_thrust_n, float))
    vh_a = hover_induced_velocity_mps(thrust, leader_rotor_radius_m, leader_n_rotors,
                                      air_density_kgpm3)
    size = np.sqrt(np.asarray(leader_n_rotors, float)) * np.asarray(leader_rotor_radius_m, float)
    vh_b = hover_induced_velocity_mps(np.asarray(follower_mass_kg, float) * gravity_mps2,
                                      follower_rotor_radius_m, follower_n_rotors,
                                      air_density_kgpm3)
    size_b = (np.sqrt(np.asarray(follower_n_rotors, float))
              * np.asarray(follower_rotor_radius_m, float))
    return np.stack(np.broadcast_arrays(vh_a, size, vh_b, size_b), axis=-1).astype(float)


def feature_map(
    kind: str,
    x: np.ndarray,
    leader_R: np.ndarray,
    *,
    eps_pos_m: float = EPS_POS_M,
    eps_vel_mps: float = EPS_VEL_MPS,
    wake_scales: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """NumPy features and output map of a model kind.

    Args:
        kind: a kind of :mod:`aerodock.learning.kinds` with features (not ``"zero"``).
        x: (n, 9) ``[dp, v_A, v_B]``, world NED.
        leader_R: (n, 3, 3) leader attitude, body to world.
        eps_pos_m: radial regularisation (see the module docstring).
        eps_vel_mps: velocity-direction regularisation.
        wake_scales: (n, k) or (k,) wake scales (:data:`WAKE_SCALE_NAMES`, the first
            :data:`N_WAKE_SCALES` read); needed by the leader-aware kinds, ignored by the others.

    Returns:
        ``(z, M)``: features (n, F) and the output map (n, 3, K) taking the network's K outputs
        to the world-frame force, ``f = M @ c``. For ``"mlp"``, ``z = x`` and ``M = I``.
    """
    x, leader_R = check_inputs(x, leader_R)
    k = get_kind(kind)
    if k.world_frame:
        return x.copy(), np.broadcast_to(np.eye(3), (x.shape[0], 3, 3))
    if k.features is None:
        raise ValueError(f"no feature map for model kind {kind!r}")
    check_eps(eps_pos_m, eps_vel_mps)
    scales = check_wake_scales(wake_scales, x.shape[0], kind) if k.n_wake_scales else None
    return _array_features(k, x, leader_R, np.stack, eps_pos_m, eps_vel_mps, scales)


def feature_map_torch(
    kind: str,
    x: Any,
    leader_R: Any,
    *,
    eps_pos_m: float = EPS_POS_M,
    eps_vel_mps: float = EPS_VEL_MPS,
    wake_scales: Any = None,
) -> tuple[Any, Any]:
    """Torch version of :func:`feature_map` (same operations; tensors in, tensors out)."""
    import torch

    k = get_kind(kind)
    if k.world_frame:
        eye = torch.eye(3, dtype=x.dtype, device=x.device)
        return x, eye.expand(x.shape[0], 3, 3)
    if k.features is None:
        raise ValueError(f"no feature map for model kind {kind!r}")
    if k.n_wake_scales and wake_scales is None:
        raise ValueError(f"model kind {kind!r} needs wake_scales (n, {k.n_wake_scales})")
    return _array_features(k, x, leader_R, torch.stack, eps_pos_m, eps_vel_mps, wake_scales)


def so2_features(
    x: np.ndarray,
    leader_R: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """The paper's ``h(x)`` (n, 6) and ``phi(x)`` (n,), radians in ``[-pi, pi]``.

    Args:
        x: (n, 9) ``[dp, v_A, v_B]``, world NED.
        leader_R: (n, 3, 3) leader attitude, body to world.
    """
    z, _ = feature_map("so2", x, leader_R)
    return z, phi_rad(x, leader_R)


def so2_ext_features(x: np.ndarray, leader_R: np.ndarray) -> np.ndarray:
    """The extended invariant features (n, 10) of kind ``"so2-ext"``
    (:mod:`aerodock.learning.kinds.so2_ext`)."""
    return feature_map("so2-ext", x, leader_R)[0]


def phi_rad(x: np.ndarray, leader_R: np.ndarray) -> np.ndarray:
    """Angle (n,) of ``proj dp`` from ``a1`` in the leader's rotor plane; 0 on the leader's axis."""
    x, leader_R = check_inputs(x, leader_R)
    dp_b = _body(x[:, 0:3], leader_R)
    return np.arctan2(dp_b[:, 1], dp_b[:, 0])


def invariant_components(
    kind: str,
    x: np.ndarray,
    leader_R: np.ndarray,
    y: np.ndarray,
    torque: np.ndarray | None = None,
    wake_scales: np.ndarray | None = None,
) -> np.ndarray:
    """World-frame forces ``y`` (n, 3) (and, for a wrench kind, torques ``torque`` (n, 3))
    expressed in a kind's output components (n, K).

    Uses ``c = M^T y`` (exact for the orthonormal columns of ``M`` away from the leader's axis);
    used to standardise the network's outputs. For a leader-aware kind, whose columns have the
    length of the force scale ``a_s``, ``c = M^T y / a_s^2`` (``wake_scales`` needed).

    Raises:
        ValueError: a wrench kind without torques, a leader-aware kind without wake scales.
    """
    _, out_map = feature_map(kind, x, leader_R, wake_scales=wake_scales)
    c = np.einsum("nik,ni->nk", out_map, np.asarray(y, dtype=float))
    k = get_kind(kind)
    if k.scaled_frame:
        c = c / np.sum(out_map[:, :, -1] ** 2, axis=1)[:, None]  # the a3 column: |a_s a3|^2
    if not k.torque:
        return c
    if torque is None:
        raise ValueError(f"model kind {kind!r} needs torque labels")
    return np.concatenate([c, np.einsum("nik,ni->nk", out_map, np.asarray(torque, float))], 1)
