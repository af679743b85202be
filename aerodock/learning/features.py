"""SO(2)-invariant feature maps (the paper's Eq. ``featuremap``) and their extended variant.

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

Extended features (kind ``"so2-ext"``, 10 features). The paper's unsigned cosine cannot tell on
which side of ``proj dp`` the follower's velocity lies, so a model on ``h`` cannot express a
tangential planar force (e.g. the wake skewing sideways when the follower moves across it). The
extension replaces the cosine by the signed pair (cos, sin) of the angle from ``proj dp`` to
``proj v_B`` and adds the leader's velocity relative to ``phi`` (the wake trails behind a moving
leader)::

    ( cos_B, sin_B, |proj dp|, |proj v_B|, a3 . dp, a3 . v_B,
      |proj v_A|, cos_A, sin_A, a3 . v_A )

with the same regularisation (``sin_B = (proj dp x proj v_B)_3 / (...)``, and likewise for
``v_A``). All of them are invariant under rotations about ``a3``.

Wrench kind (``"so2-wrench"``): the same 10 features and frame ``(e_r, e_t, a3)``, and six outputs,
the force's and the torque's components in that frame::

    f   = s(rho) (f_r e_r' + f_t e_t') + f_a a3                (m/s², world NED)
    tau = s(rho) (tau_r e_r' + tau_t e_t') + tau_a a3          (N m, world NED)

(``e_r'``, ``e_t'`` the unit radial and tangential vectors). A torque is an axial vector, but the
symmetry is a rotation about ``a3`` (no reflection), under which it turns like the force: rotating
the scene about the leader's axis rotates both predictions. The wake's torque on a follower off
the axis points along ``+e_t`` (it pushes the rotors nearer the axis down). Labels are measured in
the follower's body frame and rotated to the world frame with its attitude before training.

Leader-aware kind (``"so2-leader"``). The paper's ``h`` carries nothing of the leader's thrust or
size, so a model on it trained on a small and a large leader learns their average. This kind
takes, besides ``x`` and ``leader_R``, three **wake scales** per sample (n, 3), all invariant
scalars (:data:`WAKE_SCALE_NAMES`, built by :func:`wake_scales` from the vehicles)::

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
invariant, so the equivariance of ``"so2"`` carries over unchanged; with one leader and one
follower the features are a fixed rescaling of ``h``.

Pair-aware kind (``"so2-pair"``): ``"so2-leader"`` with a seventh feature, the follower's size
in units of the leader's, ``L_B / L_A`` (``L_B = sqrt(n_B) R_B``, the fourth wake scale). The
force scale ``a_s`` assumes the follower's rotors take the wake whole; a follower as wide as the
wake or wider does not (it averages the jet over its disks, and part of it falls beside them), and
``L_B / L_A`` is the invariant that says how much. Still invariant: the equivariance holds.

Kind ``"mlp"`` (the baseline) uses ``x`` itself, in the world frame, with an identity output map.

The implementations below are written once, generically, and run on NumPy arrays (the runtime)
or torch tensors (training, ONNX export), so the two agree by construction. This module does not
import torch at module level.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

FEATURE_VERSION = 1
EPS_POS_M = 1e-3
EPS_VEL_MPS = 1e-2

KINDS = ("so2", "so2-ext", "so2-wrench", "so2-leader", "so2-pair", "mlp", "zero")
LEADER_KINDS = ("so2-leader", "so2-pair")
"""Kinds that take the wake scales (:data:`WAKE_SCALE_NAMES`) as a third input."""
WAKE_SCALE_NAMES = ("leader_vh_mps", "leader_size_m", "follower_vh_mps", "follower_size_m")
"""The wake scales' columns: the leader's hover induced velocity (m/s), its wake's width scale
``sqrt(n) R`` (m), the follower's hover induced velocity (m/s) and its size ``sqrt(n) R`` (m).
:func:`wake_scales` builds all four; a kind reads the first :data:`N_WAKE_SCALES` of them."""
N_WAKE_SCALES = {"so2-leader": 3, "so2-pair": 4}
"""How many of the wake scales (the first ones) each leader-aware kind takes."""
AIR_DENSITY_KGPM3 = 1.225
GRAVITY_MPS2 = 9.81
TORQUE_KINDS = ("so2-wrench",)
"""Kinds that also predict the wake's torque (their outputs: force components, then torque's)."""
N_FEATURES = {"so2": 6, "so2-ext": 10, "so2-wrench": 10, "so2-leader": 6, "so2-pair": 7,
              "mlp": 9, "zero": 0}
N_OUTPUTS = {"so2": 2, "so2-ext": 3, "so2-wrench": 6, "so2-leader": 2, "so2-pair": 2, "mlp": 3,
             "zero": 0}
FEATURE_NAMES: dict[str, tuple[str, ...]] = {
    "so2": (
        "cos_dp_vB", "rho_dp_m", "rho_vB_mps", "axial_dp_m", "axial_vB_mps", "rho_vA_mps",
    ),
    "so2-ext": (
        "cos_dp_vB", "sin_dp_vB", "rho_dp_m", "rho_vB_mps", "axial_dp_m", "axial_vB_mps",
        "rho_vA_mps", "cos_dp_vA", "sin_dp_vA", "axial_vA_mps",
    ),
    "so2-wrench": (
        "cos_dp_vB", "sin_dp_vB", "rho_dp_m", "rho_vB_mps", "axial_dp_m", "axial_vB_mps",
        "rho_vA_mps", "cos_dp_vA", "sin_dp_vA", "axial_vA_mps",
    ),
    "so2-leader": (
        "cos_dp_vB", "rho_dp_per_size", "rho_vB_per_vh", "axial_dp_per_size", "axial_vB_per_vh",
        "rho_vA_per_vh",
    ),
    "so2-pair": (
        "cos_dp_vB", "rho_dp_per_size", "rho_vB_per_vh", "axial_dp_per_size", "axial_vB_per_vh",
        "rho_vA_per_vh", "follower_size_per_size",
    ),
    "mlp": (
        "dp_n_m", "dp_e_m", "dp_d_m", "vA_n_mps", "vA_e_mps", "vA_d_mps",
        "vB_n_mps", "vB_e_mps", "vB_d_mps",
    ),
    "zero": (),
}
OUTPUT_NAMES: dict[str, tuple[str, ...]] = {
    "so2": ("f_radial_mps2", "f_axial_mps2"),
    "so2-ext": ("f_radial_mps2", "f_tangential_mps2", "f_axial_mps2"),
    "so2-wrench": ("f_radial_mps2", "f_tangential_mps2", "f_axial_mps2",
                   "tau_radial_nm", "tau_tangential_nm", "tau_axial_nm"),
    "so2-leader": ("f_radial_per_scale", "f_axial_per_scale"),
    "so2-pair": ("f_radial_per_scale", "f_axial_per_scale"),
    "mlp": ("f_n_mps2", "f_e_mps2", "f_d_mps2"),
    "zero": (),
}
# Lower bounds on the standard deviations used to standardise each feature (in the feature's
# units). A feature that barely varies in the training data (the leader always hovering: |v_A| of
# a few mm/s) must not be blown up to hundreds of standard deviations when it does vary in use.
_POS_FLOOR_M, _VEL_FLOOR_MPS, _ANGLE_FLOOR = 0.05, 0.05, 0.1
SCALE_FLOOR: dict[str, tuple[float, ...]] = {
    "so2": (_ANGLE_FLOOR, _POS_FLOOR_M, _VEL_FLOOR_MPS, _POS_FLOOR_M, _VEL_FLOOR_MPS,
            _VEL_FLOOR_MPS),
    "so2-ext": (_ANGLE_FLOOR, _ANGLE_FLOOR, _POS_FLOOR_M, _VEL_FLOOR_MPS, _POS_FLOOR_M,
                _VEL_FLOOR_MPS, _VEL_FLOOR_MPS, _ANGLE_FLOOR, _ANGLE_FLOOR, _VEL_FLOOR_MPS),
    "so2-wrench": (_ANGLE_FLOOR, _ANGLE_FLOOR, _POS_FLOOR_M, _VEL_FLOOR_MPS, _POS_FLOOR_M,
                   _VEL_FLOOR_MPS, _VEL_FLOOR_MPS, _ANGLE_FLOOR, _ANGLE_FLOOR, _VEL_FLOOR_MPS),
    # dimensionless: 1 leader size (about 5 cm on a Crazyflie), 0.01 v_h (about 4 cm/s)
    "so2-leader": (_ANGLE_FLOOR, 1.0, 0.01, 1.0, 0.01, 0.01),
    # the size ratio: 0.1 (a follower a tenth of the leader's size apart)
    "so2-pair": (_ANGLE_FLOOR, 1.0, 0.01, 1.0, 0.01, 0.01, 0.1),
    "mlp": (_POS_FLOOR_M,) * 3 + (_VEL_FLOOR_MPS,) * 6,
    "zero": (),
}
# Features standardised with one shared scale (indices into a kind's features). The MLP's inputs
# are world vectors: the horizontal components of each (north, east) share one scale, so that
# standardising keeps a rotation of the scene about the vertical a rotation (a pass flown
# north-south looks, to the network, like the same pass flown east-west; with a scale per axis
# the axis the training flights hardly moved along is magnified). Features not listed here have
# their own scale.
SCALE_GROUPS: dict[str, tuple[tuple[int, ...], ...]] = {
    "mlp": ((0, 1), (3, 4), (6, 7)),
}


def check_kind(kind: str) -> str:
    """Return ``kind`` if it is a known model kind.

    Raises:
        ValueError: unknown kind.
    """
    if kind not in KINDS:
        raise ValueError(f"unknown model kind {kind!r} (expected one of {', '.join(KINDS)})")
    return kind


def _body(w: Any, rot: Any) -> Any:
    """Leader-body coordinates ``R^T w`` of world vectors ``w`` (n, 3), for arrays or tensors."""
    return (rot * w[..., :, None]).sum(-2)


def _feature_map_generic(
    kind: str, x: Any, rot: Any, stack: Callable[..., Any], eps_pos_m: float, eps_vel_mps: float,
    scales: Any = None,
) -> tuple[Any, Any]:
    """Features ``z`` (n, F) and output map ``M`` (n, 3, K) for one array library.

    The world-frame prediction is ``f = M @ c`` where ``c`` (n, K) are the network's outputs
    (for a wrench kind, ``M`` maps the force's K and the torque's K outputs alike).
    Only arithmetic, ``** 0.5``, slicing, ``sum`` and ``stack`` are used so that NumPy, torch and
    the ONNX exporter all see the same operations.
    """
    dp_b = _body(x[..., 0:3], rot)
    va_b = _body(x[..., 3:6], rot)
    vb_b = _body(x[..., 6:9], rot)
    px, py, pz = dp_b[..., 0], dp_b[..., 1], dp_b[..., 2]
    ax, ay, az = va_b[..., 0], va_b[..., 1], va_b[..., 2]
    bx, by, bz = vb_b[..., 0], vb_b[..., 1], vb_b[..., 2]
    rho2 = px * px + py * py
    rho = rho2**0.5
    rho_soft = (rho2 + eps_pos_m * eps_pos_m) ** 0.5
    ur_x, ur_y = px / rho_soft, py / rho_soft  # soft unit radial vector in (a1, a2) coordinates
    vb2 = bx * bx + by * by
    va2 = ax * ax + ay * ay
    vb_soft = (vb2 + eps_vel_mps * eps_vel_mps) ** 0.5
    cos_b = (ur_x * bx + ur_y * by) / vb_soft
    a1, a2, a3 = rot[..., :, 0], rot[..., :, 1], rot[..., :, 2]
    e_r = a1 * ur_x[..., None] + a2 * ur_y[..., None]  # world, |e_r| = s(rho)
    if kind == "so2":
        z = stack([cos_b, rho, vb2**0.5, pz, bz, va2**0.5], -1)
        out_map = stack([e_r, a3], -1)
    elif kind in LEADER_KINDS:
        vh_a, size_a, vh_b = scales[..., 0], scales[..., 1], scales[..., 2]
        ratio = vh_a / vh_b
        accel_scale = (ratio * ratio * GRAVITY_MPS2)[..., None]
        parts = [cos_b, rho / size_a, vb2**0.5 / vh_a, pz / size_a, bz / vh_a, va2**0.5 / vh_a]
        if kind == "so2-pair":
            parts.append(scales[..., 3] / size_a)
        z = stack(parts, -1)
        out_map = stack([e_r * accel_scale, a3 * accel_scale], -1)
    elif kind in ("so2-ext", "so2-wrench"):
        va_soft = (va2 + eps_vel_mps * eps_vel_mps) ** 0.5
        sin_b = (ur_x * by - ur_y * bx) / vb_soft
        cos_a = (ur_x * ax + ur_y * ay) / va_soft
        sin_a = (ur_x * ay - ur_y * ax) / va_soft
        z = stack([cos_b, sin_b, rho, vb2**0.5, pz, bz, va2**0.5, cos_a, sin_a, az], -1)
        e_t = a2 * ur_x[..., None] - a1 * ur_y[..., None]
        out_map = stack([e_r, e_t, a3], -1)
    else:
        raise ValueError(f"no feature map for model kind {kind!r}")
    return z, out_map


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
    k = N_WAKE_SCALES[kind]
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
    """The wake scales (n, 4) of the leader-aware kinds (see the module docstring).

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
        kind: ``"so2"``, ``"so2-ext"``, ``"so2-wrench"``, ``"so2-leader"``, ``"so2-pair"`` or
            ``"mlp"``.
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
    if kind == "mlp":
        return x.copy(), np.broadcast_to(np.eye(3), (x.shape[0], 3, 3))
    check_eps(eps_pos_m, eps_vel_mps)
    scales = check_wake_scales(wake_scales, x.shape[0], kind) if kind in LEADER_KINDS else None
    return _feature_map_generic(kind, x, leader_R, np.stack, eps_pos_m, eps_vel_mps, scales)


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

    if kind == "mlp":
        eye = torch.eye(3, dtype=x.dtype, device=x.device)
        return x, eye.expand(x.shape[0], 3, 3)
    if kind in LEADER_KINDS and wake_scales is None:
        raise ValueError(f"model kind {kind!r} needs wake_scales (n, {N_WAKE_SCALES[kind]})")
    return _feature_map_generic(kind, x, leader_R, torch.stack, eps_pos_m, eps_vel_mps,
                                wake_scales)


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
    """The extended invariant features (n, 10) of kind ``"so2-ext"`` (see the module docstring)."""
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
    if kind in LEADER_KINDS:
        c = c / np.sum(out_map[:, :, -1] ** 2, axis=1)[:, None]  # the a3 column: |a_s a3|^2
    if kind not in TORQUE_KINDS:
        return c
    if torque is None:
        raise ValueError(f"model kind {kind!r} needs torque labels")
    return np.concatenate([c, np.einsum("nik,ni->nk", out_map, np.asarray(torque, float))], 1)
