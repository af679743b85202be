"""NumPy-only runtime for trained downwash models (what the follower's controller runs).

This module never imports PyTorch: a Raspberry Pi class computer only needs NumPy to run a model
directory written by :mod:`aerodock.learning.train`. The input standardisation and output scaling
are folded into the first and last layers at load time, and computation is in float64 (the
stored float32 weights are exact in float64).

Two paths give the same numbers (to rounding):

* :meth:`Predictor.predict` -- batched, ``x (n, 9)``, ``leader_R (n, 3, 3)`` -> ``(n, 3)``; a
  sample's prediction is the same to the bit in a batch of any size (:data:`ROW_BLOCK`);
* :meth:`Predictor.predict_one` -- one sample, ``x (9,)``, ``leader_R (3, 3)`` -> ``(3,)``; the
  features are computed with Python floats and the layers write into preallocated buffers, so a
  call costs tens of microseconds, not the ~100 us of the batched path's per-op overhead (for a
  deployed follower; its last bits may differ from the batched path's).

The controller's feed-forward uses :meth:`Predictor.predict_bodies` (the batched path, so that a
trial flies the same numbers alone and in a campaign) with the leader's and the follower's
:class:`~aerodock.downwash.base.BodyState`::

    predictor = Predictor.load("models/so2")          # or load_predictor(path_or_None)
    f_ext_hat_mps2 = predictor.predict_bodies(leader, follower)   # (n, 3), m/s^2, NED
    u[:, :3] -= f_ext_hat_mps2

A ``so2-wrench`` model also predicts the wake's torque (:attr:`Predictor.has_torque`):
:meth:`Predictor.predict_torque` in the world frame (N m, NED) and
:meth:`Predictor.predict_torque_bodies` in the follower's body frame (N m, FRD), what the
autopilot's torque feed-forward subtracts (:mod:`aerodock.control.torque_feedforward`).

A leader-aware model (``so2-leader``, ``so2-pair``, :attr:`Predictor.needs_wake_scales`) takes a
third input, the wake scales (n, k) of :func:`aerodock.learning.features.wake_scales` (it reads the
first :data:`~aerodock.learning.features.N_WAKE_SCALES`; more may be given). Where they come from:

* :meth:`Predictor.predict` / :meth:`Predictor.predict_one`: the caller's ``wake_scales``, or,
  when none are given, :attr:`Predictor.default_wake_scales`: the median of the training data's
  (``model.json`` -> ``training.wake_scales.default``, the training pairing's hover scales).
* :meth:`Predictor.predict_bodies`: from the :class:`BodyState`: the leader's
  ``thrust_n`` (its hover thrust ``mass_kg * g`` where that is not finite and positive) and the
  follower's ``mass_kg``, with the rotor radii and counts of :attr:`Predictor.rotor_geometry`:
  the training flights' (``model.json`` -> ``vehicles``) unless set with
  :meth:`Predictor.set_rotor_geometry` (from a config). Without a known geometry (training
  flights that differ, and none set) it falls back to the default scales.

Other kinds ignore ``wake_scales``: they run exactly as before.

A follower larger than the one the model was trained on feels the wake over a wider rotor
footprint (:mod:`aerodock.learning.footprint`): :meth:`Predictor.predict` takes the follower's
motor-to-motor diagonal (``follower_diagonal_m``, per sample or one value) and averages the
prediction over the extra ring, where the model file records the training follower's diagonal
(:attr:`Predictor.trained_follower_diagonal_m`); :meth:`Predictor.predict_bodies` does the same
for the follower set with :meth:`Predictor.set_follower_diagonal`. Campaigns do not set it (the
footprint's second-order argument needs the extra ring small against the wake's width). The
footprint carries the force only; without it every path runs as before.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from aerodock.downwash.base import BodyState
from aerodock.learning.features import (
    GRAVITY_MPS2,
    check_eps,
    check_inputs,
    check_wake_scales,
    feature_map,
    wake_scales,
)
from aerodock.learning.footprint import footprint_average, footprint_radius_m
from aerodock.learning.kinds import get_kind
from aerodock.learning.kinds.trace import compile_scalar
from aerodock.learning.modelfile import MODEL_JSON, ModelFileError, ModelSpec, load_model_dir


def _act_inplace(name: str, h: np.ndarray) -> np.ndarray:
    if name == "tanh":
        return np.tanh(h, out=h)
    # SiLU: h * sigmoid(h) with sigmoid(h) = (1 + tanh(h / 2)) / 2 (no overflow for large |h|).
    s = np.tanh(0.5 * h)
    s += 1.0
    s *= 0.5
    h *= s
    return h



def bodies_to_inputs(leader: BodyState, follower: BodyState) -> tuple[np.ndarray, np.ndarray]:
    """Model inputs ``x = [p_B - p_A, v_A, v_B]`` (n, 9) and ``leader_R`` (n, 3, 3)."""
    lp, fp = np.asarray(leader.p, dtype=float), np.asarray(follower.p, dtype=float)
    if lp.ndim == 1:
        lp, fp = lp[None], fp[None]
    x = np.concatenate(
        [fp - lp, np.reshape(leader.v, lp.shape), np.reshape(follower.v, fp.shape)], axis=1
    )
    return x, np.reshape(np.asarray(leader.R, dtype=float), (lp.shape[0], 3, 3))


ROW_BLOCK = 8
"""The batched path's layers run on a multiple of this many samples (the features padded with
copies of the first sample's): NumPy's matrix products (OpenBLAS) round a row's sums otherwise
in a batch of one (a matrix-vector kernel) and in the rows left over from its matrix kernel's
blocks, so a sample's prediction, and a trial's flight with the model in the loop, depended on
how many samples were predicted beside it (by 1e-16 relative a product; this machine, NumPy
2.4, every layer shape from 2 to 64 wide: a multiple of 8 rows gives every row the same sums).
A sample's features are its own arithmetic whatever the batch, so they are computed for the
batch as it is."""


class Predictor:
    """A trained downwash model, NumPy only.

    ``predict_one`` reuses preallocated buffers: one Predictor per thread (loading is cheap).

    Attributes:
        kind: the model's kind (:mod:`aerodock.learning.kinds`).
        spec: the model's :class:`~aerodock.learning.modelfile.ModelSpec`.
        meta: the model's ``model.json`` document (training summary etc.).
        has_torque: the model also predicts the wake's torque (``"so2-wrench"``).
        trained_follower_diagonal_m: the training follower's motor-to-motor diagonal (m), from
            ``model.json``'s ``vehicles``; None when unknown or when the flights' differ.
    """

    def __init__(
        self,
        spec: ModelSpec,
        weights: list[tuple[np.ndarray, np.ndarray]],
        meta: dict[str, Any] | None = None,
    ) -> None:
        """Build from a spec and ``[(W, b), ...]`` (torch ``Linear`` layout)."""
        self.spec = spec
        self.kind = spec.kind
        record = get_kind(spec.kind)
        self.has_torque = record.torque
        self.needs_wake_scales = bool(record.n_wake_scales)
        self.meta = dict(meta or {})
        self.default_wake_scales = _recorded_wake_scales(self.meta, spec.kind)
        self.rotor_geometry = _recorded_rotor_geometry(self.meta)
        self.trained_follower_diagonal_m = _recorded_follower_diagonal(self.meta)
        self.follower_diagonal_m: float | None = None  # the flying follower's, once set
        self._footprint_m = 0.0  # the ring :meth:`predict_bodies` averages over (0: none)
        if not get_kind(spec.kind).has_network:
            self._layers: list[tuple[np.ndarray, np.ndarray]] = []
            return
        check_eps(spec.eps_pos_m, spec.eps_vel_mps)
        if len(weights) != len(spec.weight_shapes()):
            raise ValueError("weights do not match the spec's layer sizes")
        layers = folded_layers(spec, weights)
        with np.errstate(over="ignore", invalid="ignore"):
            finite = all(np.all(np.isfinite(w)) and np.all(np.isfinite(b)) for w, b in layers)
        if not finite:
            raise ValueError("weights and normalisation overflow to non-finite values")
        self._layers = [(np.ascontiguousarray(w), np.ascontiguousarray(b)) for w, b in layers]
        self._ego, self._phi_layers = record.ego_features, record.phi_layers
        self._layers_t = [(np.ascontiguousarray(w.T), b) for w, b in self._layers]
        self._act = spec.activation
        self._z = np.zeros(record.n_features)
        self._world_frame = record.world_frame
        if not self._world_frame and not self.needs_wake_scales:
            self._predict_scalar = compile_scalar(record, spec.eps_pos_m**2,
                                                  spec.eps_vel_mps**2)
        self._bufs = [np.zeros(w.shape[0]) for w, _ in self._layers]

    @classmethod
    def load(cls, path: str | Path) -> Predictor:
        """Load a model directory (a :class:`ZeroPredictor` for a ``"zero"`` model).

        Raises:
            ModelFileError: missing, corrupt or mismatched model files, or values the runtime
                cannot use (e.g. feature constants out of range); one line naming the file.
        """
        where = Path(path)
        if where.name != MODEL_JSON:
            where = where / MODEL_JSON
        try:
            spec, weights, doc = load_model_dir(path)
            if not get_kind(spec.kind).has_network:
                return ZeroPredictor(meta=doc)
            return cls(spec, weights, doc)
        except ModelFileError:
            raise
        except RecursionError:
            raise ModelFileError(f"{where}: nested too deeply (corrupt model file)") from None
        except (ValueError, TypeError, OverflowError) as err:
            raise ModelFileError(f"{where}: {' '.join(str(err).split())}") from None

    def set_rotor_geometry(self, leader_rotor_radius_m: float, leader_n_rotors: int,
                           follower_rotor_radius_m: float, follower_n_rotors: int) -> None:
        """The vehicles' rotors :meth:`predict_bodies` builds a leader-aware model's wake scales
        with (e.g. a config's ``[leader]`` and ``[vehicle]``), instead of the training
        flights'."""
        values = (leader_rotor_radius_m, leader_n_rotors, follower_rotor_radius_m,
                  follower_n_rotors)
        if not all(np.isfinite(float(v)) and float(v) > 0 for v in values):
            raise ValueError(f"rotor geometry must be positive numbers, got {values}")
        self.rotor_geometry = {
            "leader": (float(leader_rotor_radius_m), int(leader_n_rotors)),
            "follower": (float(follower_rotor_radius_m), int(follower_n_rotors))}

    def set_follower_diagonal(self, diagonal_m: float | None) -> None:
        """The flying follower's motor-to-motor diagonal (m): :meth:`predict_bodies` then
        predicts a follower larger than the training one over its rotor footprint
        (:mod:`aerodock.learning.footprint`; the force only). None: as trained again.

        Raises:
            ValueError: not a finite positive number (or None).
        """
        if diagonal_m is None:
            self.follower_diagonal_m, self._footprint_m = None, 0.0
            return
        if (isinstance(diagonal_m, bool | str) or not np.isfinite(float(diagonal_m))
                or float(diagonal_m) <= 0):
            raise ValueError(f"the follower's diagonal must be a positive number of metres, "
                             f"got {diagonal_m!r}")
        self.follower_diagonal_m = float(diagonal_m)
        self._footprint_m = float(footprint_radius_m(self.trained_follower_diagonal_m,
                                                     self.follower_diagonal_m))

    def _scales(self, wake_scales: np.ndarray | None, n: int) -> np.ndarray | None:
        """The wake scales a prediction of ``n`` samples uses (None for other kinds)."""
        if not self.needs_wake_scales:
            return None
        if wake_scales is None:
            if self.default_wake_scales is None:
                raise ValueError(f"a {self.kind!r} model needs wake_scales and its model file "
                                 "records no default (training.wake_scales)")
            wake_scales = self.default_wake_scales
        return check_wake_scales(wake_scales, n, self.kind)

    def wake_scales_for_bodies(self, leader: BodyState, follower: BodyState) -> np.ndarray:
        """The wake scales (n, 4) of two vehicles' batched states (see the module docstring;
        the default scales, (n, k), when the rotor geometry is unknown).

        Raises:
            ValueError: no rotor geometry and no default scales.
        """
        n = np.reshape(np.asarray(leader.p, dtype=float), (-1, 3)).shape[0]
        if self.rotor_geometry is None:
            return self._scales(None, n)
        (r_a, n_a), (r_b, n_b) = self.rotor_geometry["leader"], self.rotor_geometry["follower"]
        thrust = np.broadcast_to(np.asarray(leader.thrust_n, float), (n,))
        hover = np.broadcast_to(np.asarray(leader.mass_kg, float), (n,)) * GRAVITY_MPS2
        thrust = np.where(np.isfinite(thrust) & (thrust > 0), thrust, hover)
        mass_b = np.broadcast_to(np.asarray(follower.mass_kg, float), (n,))
        return wake_scales(thrust, r_a, n_a, mass_b, r_b, n_b)

    # -- batched ---------------------------------------------------------------------------
    def predict(self, x: np.ndarray, leader_R: np.ndarray,
                wake_scales: np.ndarray | None = None,
                follower_diagonal_m: float | np.ndarray | None = None) -> np.ndarray:
        """Predicted downwash acceleration on the follower, (n, 3), m/s², NED.

        Args:
            x: (n, 9) ``[dp, v_A, v_B]`` (``dp = p_follower - p_leader``), NED, SI.
            leader_R: (n, 3, 3) leader attitude, body to world.
            wake_scales: (n, 3) or (3,), a leader-aware model's third input (default:
                :attr:`default_wake_scales`); ignored by other kinds.
            follower_diagonal_m: the flying follower's motor-to-motor diagonal (m), one value
                or (n,): where it is larger than :attr:`trained_follower_diagonal_m`, the
                prediction is averaged over the extra rotor footprint
                (:mod:`aerodock.learning.footprint`); None (or an unknown training diagonal):
                the model's own prediction. The force only: :meth:`predict_wrench` and
                :meth:`predict_torque` predict as trained.
        """
        radius = footprint_radius_m(self.trained_follower_diagonal_m, follower_diagonal_m)
        if np.any(radius > 0):
            x, leader_R = check_inputs(x, leader_R)
            if wake_scales is None or not self.needs_wake_scales:
                return footprint_average(self.predict, x, leader_R, radius)
            scales = self._scales(wake_scales, x.shape[0])
            return footprint_average(self.predict, x, leader_R, radius, scales)
        if wake_scales is None:  # the call of every kind but the leader-aware ones, unchanged
            return self.predict_wrench(x, leader_R)[0]
        return self.predict_wrench(x, leader_R, wake_scales)[0]

    __call__ = predict

    def predict_torque(self, x: np.ndarray, leader_R: np.ndarray) -> np.ndarray:
        """Predicted wake torque on the follower about its centre of mass, (n, 3), N m, world
        NED (inputs as :meth:`predict`).

        Raises:
            ValueError: the model predicts no torque (see :attr:`has_torque`).
        """
        if not self.has_torque:
            raise ValueError(f"a {self.kind!r} model predicts no torque (train 'so2-wrench')")
        return self.predict_wrench(x, leader_R)[1]

    def predict_wrench(self, x: np.ndarray, leader_R: np.ndarray,
                       wake_scales: np.ndarray | None = None
                       ) -> tuple[np.ndarray, np.ndarray | None]:
        """(force (n, 3) m/s², torque (n, 3) N m or None without one), world NED; each
        sample's the same to the bit whatever the batch (:data:`ROW_BLOCK`)."""
        x, leader_R = check_inputs(x, leader_R)
        n = x.shape[0]
        if self._world_frame:
            z, out_map = x, None
        else:
            z, out_map = feature_map(
                self.kind, x, leader_R,
                eps_pos_m=self.spec.eps_pos_m, eps_vel_mps=self.spec.eps_vel_mps,
                wake_scales=self._scales(wake_scales, n),
            )
        pad = -n % ROW_BLOCK
        if pad:  # the layers' rows padded with copies of the first sample's features (a
            # sample's features are its own arithmetic, whatever the batch)
            z = np.concatenate([z, np.repeat(z[:1], pad, axis=0)])
        h, ego = (z, None) if not self._ego else (z[:, :-self._ego], z[:, -self._ego:])
        for i, (wt, b) in enumerate(self._layers_t):
            if ego is not None and i == self._phi_layers:  # deep sets: rho(phi(...), ego)
                h = np.concatenate([h, ego], axis=1)
            h = h @ wt
            h += b
            if i < len(self._layers_t) - 1:
                _act_inplace(self._act, h)
        if pad:
            h = h[:n]
        if out_map is None:
            return h, None
        if not self.has_torque:
            return np.einsum("nik,nk->ni", out_map, h), None
        k = out_map.shape[-1]
        return (np.einsum("nik,nk->ni", out_map, h[:, :k]),
                np.einsum("nik,nk->ni", out_map, h[:, k:]))

    # -- one sample --------------------------------------------------------------------------
    def _mlp_one(self, feats: tuple[float, ...] | list[float]) -> list[float]:
        z = self._z
        z[:] = feats
        h = z if not self._ego else z[:-self._ego]
        last = len(self._layers) - 1
        for i, ((w, b), buf) in enumerate(zip(self._layers, self._bufs)):
            if self._ego and i == self._phi_layers:  # deep sets: rho(phi(...), ego)
                h = np.concatenate([h, z[-self._ego:]])
            np.dot(w, h, out=buf)
            buf += b
            if i < last:
                if self._act == "tanh":
                    np.tanh(buf, out=buf)
                else:
                    _act_inplace(self._act, buf)
            h = buf
        return h.tolist()

    def predict_one(self, x: np.ndarray, leader_R: np.ndarray,
                    wake_scales: np.ndarray | None = None) -> np.ndarray:
        """One sample: ``x`` (9,), ``leader_R`` (3, 3) -> (3,) m/s², NED (see :meth:`predict`;
        ``wake_scales`` (k,) a leader-aware model's, which runs through the batched path)."""
        if self.needs_wake_scales:
            return self.predict(np.reshape(x, (1, 9)), np.reshape(leader_R, (1, 3, 3)),
                                None if wake_scales is None else np.reshape(wake_scales, (1, -1))
                                )[0]
        xs = np.asarray(x, dtype=float).reshape(9).tolist()
        if self._world_frame:
            return np.array(self._mlp_one(xs))
        rs = np.asarray(leader_R, dtype=float).reshape(3, 3).tolist()
        return np.array(self._predict_scalar(xs, rs, self._mlp_one))

    # -- controller interface ------------------------------------------------------------------
    def predict_bodies(self, leader: BodyState, follower: BodyState) -> np.ndarray:
        """Feed-forward ``f_ext`` (n, 3), m/s², NED, from the two vehicles' batched states."""
        x, rot = bodies_to_inputs(leader, follower)
        footprint = {"follower_diagonal_m": self.follower_diagonal_m} if self._footprint_m else {}
        if self.needs_wake_scales:
            return self.predict(x, rot, self.wake_scales_for_bodies(leader, follower), **footprint)
        if footprint:
            return self.predict(x, rot, **footprint)
        return self.predict(x, rot)

    def predict_torque_bodies(self, leader: BodyState, follower: BodyState) -> np.ndarray:
        """Predicted wake torque (n, 3), N m, in the follower's body frame (FRD, about its
        centre of mass), from the two vehicles' batched states.

        Raises:
            ValueError: the model predicts no torque (see :attr:`has_torque`).
        """
        x, rot = bodies_to_inputs(leader, follower)
        torque = self.predict_torque(x, rot)  # no torque kind is leader-aware
        follower_rot = np.reshape(np.asarray(follower.R, dtype=float), (x.shape[0], 3, 3))
        return np.einsum("nji,nj->ni", follower_rot, torque)  # R^T tau


def folded_layers(spec: ModelSpec, weights: list[tuple[np.ndarray, np.ndarray]]
                  ) -> list[tuple[np.ndarray, np.ndarray]]:
    """``[(W, b), ...]`` (float64) with the input standardisation folded into the layers that
    read the features (the first; a deep-sets kind's first ``rho`` layer for the ego features)
    and the output scaling into the last: the network then maps raw features to raw outputs.
    Values may overflow (the caller checks them)."""
    layers = [(np.array(w, dtype=np.float64), np.array(b, dtype=np.float64)) for w, b in weights]
    in_std = np.asarray(spec.in_std, dtype=np.float64)
    in_mean = np.asarray(spec.in_mean, dtype=np.float64)
    record = get_kind(spec.kind)
    e = record.ego_features
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        w0, b0 = layers[0]
        w0 = w0 / in_std[None, :in_std.shape[0] - e]
        b0 = b0 - w0 @ in_mean[:in_mean.shape[0] - e]
        layers[0] = (w0, b0)
        if e:
            wp, bp = layers[record.phi_layers]
            w_ego = wp[:, -e:] / in_std[None, -e:]
            layers[record.phi_layers] = (np.concatenate([wp[:, :-e], w_ego], axis=1),
                                         bp - w_ego @ in_mean[-e:])
        wl, bl = layers[-1]
        out_std = np.asarray(spec.out_std, dtype=np.float64)
        layers[-1] = (out_std[:, None] * wl, out_std * bl + np.asarray(spec.out_mean, float))
    return layers


def _recorded_wake_scales(meta: dict[str, Any], kind: str) -> np.ndarray | None:
    """``training.wake_scales.default`` of a leader-aware model's document (k,), or None."""
    training = meta.get("training")
    record = training.get("wake_scales") if isinstance(training, dict) else None
    default = record.get("default") if isinstance(record, dict) else None
    try:
        arr = np.asarray(default, dtype=float)
    except (TypeError, ValueError):
        return None
    k = get_kind(kind).n_wake_scales
    return arr if k and arr.shape == (k,) and np.all(np.isfinite(arr) & (arr > 0)) else None


def _recorded_rotor_geometry(meta: dict[str, Any]) -> dict[str, tuple[float, int]] | None:
    """The training vehicles' ``{"leader": (rotor_radius_m, n_rotors), "follower": ...}`` from a
    model document's ``vehicles``, or None unless both are single known values."""
    vehicles = meta.get("vehicles")
    if not isinstance(vehicles, dict):
        return None
    out = {}
    for role in ("leader", "follower"):
        entry = vehicles.get(role)
        if not isinstance(entry, dict):
            return None
        radius, count = entry.get("rotor_radius_m"), entry.get("n_rotors")
        if not isinstance(radius, int | float) or not isinstance(count, int | float):
            return None
        out[role] = (float(radius), int(count))
    return out


def _recorded_follower_diagonal(meta: dict[str, Any]) -> float | None:
    """The training follower's diagonal (m) from a model document's ``vehicles``, or None
    unless it is one known positive value."""
    vehicles = meta.get("vehicles")
    follower = vehicles.get("follower") if isinstance(vehicles, dict) else None
    value = follower.get("diagonal_m") if isinstance(follower, dict) else None
    if isinstance(value, int | float) and not isinstance(value, bool) and value > 0:
        return float(value)
    return None


class ZeroPredictor(Predictor):
    """The zero model: predicts no downwash (the "without model" baseline)."""

    def __init__(self, meta: dict[str, Any] | None = None) -> None:
        """A zero model (``meta`` is an optional ``model.json`` document)."""
        super().__init__(ModelSpec(kind="zero"), [], meta)

    def predict(self, x: np.ndarray, leader_R: np.ndarray,
                wake_scales: np.ndarray | None = None,
                follower_diagonal_m: float | np.ndarray | None = None) -> np.ndarray:
        """Zeros (n, 3)."""
        x, _ = check_inputs(x, leader_R)
        return np.zeros((x.shape[0], 3))

    __call__ = predict

    def predict_wrench(self, x: np.ndarray, leader_R: np.ndarray,
                       wake_scales: np.ndarray | None = None) -> tuple[np.ndarray, None]:
        """Zeros (n, 3), and no torque."""
        return self.predict(x, leader_R), None

    def predict_one(self, x: np.ndarray, leader_R: np.ndarray,
                    wake_scales: np.ndarray | None = None) -> np.ndarray:
        """Zeros (3,)."""
        return np.zeros(3)

    def predict_bodies(self, leader: BodyState, follower: BodyState) -> np.ndarray:
        """Zeros (n, 3)."""
        return np.zeros((np.reshape(leader.p, (-1, 3)).shape[0], 3))


def load_predictor(path: str | Path | None) -> Predictor:
    """A predictor for a model directory, or the :class:`ZeroPredictor` for ``None``."""
    return ZeroPredictor() if path is None else Predictor.load(path)


class PredictorField:
    """A trained model seen as a (deterministic) downwash field, e.g. for ``field probe``.

    Implements the :class:`~aerodock.downwash.base.DownwashField` protocol.
    """

    def __init__(self, predictor: Predictor) -> None:
        """Wrap ``predictor``."""
        self.predictor = predictor

    def reset(self, n: int, rng: np.random.Generator) -> None:
        """Nothing to reset (the model has no turbulence state)."""

    def acceleration(self, leader: BodyState, follower: BodyState, dt: float) -> np.ndarray:
        """(n, 3) predicted acceleration on the follower, m/s², NED."""
        return self.predictor.predict_bodies(leader, follower)
