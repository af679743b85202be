"""Training data sets: model inputs, leader attitudes and labels, built from FlightLogs.

A :class:`Dataset` holds, for n samples of one or more flights, ``x = [dp, v_A, v_B]`` (n, 9)
with ``dp = p_follower - p_leader`` (world NED), the leader's attitude ``leader_R`` (n, 3, 3,
body to world), the de-biased labels ``y`` (n, 3, m/s², NED, see :mod:`aerodock.learning.labels`),
the flight each sample comes from and its time. Simulated flights may also provide the true mean
downwash acceleration (``extra["true_field_mean_mps2"]`` in the FlightLog) as ``y_true_mean``.

Flights that log the follower's torques (:mod:`aerodock.learning.labels`) also give torque
labels ``y_torque`` (n, 3), N m, rotated from the follower's body frame into the world frame
(NED) with its logged attitude, so that they transform under the SO(2) symmetry as the force
does; simulated ones give the true wake torque the same way as ``y_torque_true`` (evaluation
only). Flights without them have NaN rows there.

Data set files are read and written by :mod:`aerodock.learning.datafiles`; train/validation
splits and subsets are made by :mod:`aerodock.learning.splits`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from aerodock.flightlog import FlightLog
from aerodock.geometry import quat_to_rotmat
from aerodock.learning.features import (
    AIR_DENSITY_KGPM3,
    GRAVITY_MPS2,
    WAKE_SCALE_NAMES,
    wake_scales,
)
from aerodock.learning.labels import (
    BiasEstimate,
    free_air_radius_of,
    has_torque,
    labels_from_logs,
    torque_labels_from_logs,
    valid_mask,
)
from aerodock.learning.training_vehicles import flight_vehicle_fields, vehicles_from_flights

TRUE_FIELD_KEY = "true_field_mean_mps2"
TRUE_TORQUE_KEY = "true_wake_torque_nm"
# Optional (n, 3) arrays of a Dataset (NaN rows for flights without them).
OPTIONAL_ARRAYS = ("y_true_mean", "y_torque", "y_torque_true")
# Optional (n,) arrays of a Dataset (NaN for flights without them).
OPTIONAL_SCALARS = ("leader_thrust_n",)
LEADER_THRUST_KEY = "leader_thrust_n"
INTERACTION_RADIUS_M = 0.2


class DataError(ValueError):
    """Training/evaluation data could not be read or built; the message names the file."""


@dataclass(frozen=True, eq=False)
class Dataset:
    """Samples of model input, leader attitude and label (batch-first, world NED, SI).

    Attributes:
        x: (n, 9) ``[dp, v_A, v_B]``: relative position (m), leader and follower velocity (m/s).
        leader_R: (n, 3, 3) leader attitude, body to world.
        y: (n, 3) labels, m/s².
        flight_id: (n,) index into ``meta["flights"]``.
        t_s: (n,) time within the flight, s.
        y_true_mean: (n, 3) the simulator's true mean downwash acceleration (NaN rows for
            flights without it), or None when no flight has it.
        meta: JSON-serialisable metadata: ``flights`` (one dict per flight: name, source,
            n_samples, duration_s, dt_s, bias_mps2, bias_source, n_free_air, and with torque
            labels torque_bias_nm), ``minutes``, ``sources``, ``labels`` (label options),
            ``warnings``.
        y_torque: (n, 3) torque labels, N m, world NED (NaN rows for flights without torque
            extras), or None when no flight has them.
        y_torque_true: (n, 3) the simulator's wake torque over the same periods, N m, world NED
            (NaN rows where unknown), or None.
        leader_thrust_n: (n,) the leader's collective thrust, N, where its log has one
            (``extra["leader_thrust_n"]``: logged or commanded), NaN elsewhere; or None when no
            flight has it. Used by the leader-aware kinds (:meth:`wake_scales`).
    """

    x: np.ndarray
    leader_R: np.ndarray
    y: np.ndarray
    flight_id: np.ndarray
    t_s: np.ndarray
    y_true_mean: np.ndarray | None = None
    meta: dict[str, Any] = field(default_factory=dict)
    y_torque: np.ndarray | None = None
    y_torque_true: np.ndarray | None = None
    leader_thrust_n: np.ndarray | None = None

    def __post_init__(self) -> None:
        n = np.shape(self.x)[0] if np.ndim(self.x) == 2 else -1
        shapes = {"x": (n, 9), "leader_R": (n, 3, 3), "y": (n, 3), "flight_id": (n,), "t_s": (n,)}
        for name, shape in shapes.items():
            dtype = np.int64 if name == "flight_id" else float
            arr = np.asarray(getattr(self, name), dtype=dtype)
            if arr.shape != shape:
                raise DataError(f"dataset: {name} has shape {arr.shape}, expected {shape}")
            object.__setattr__(self, name, arr)
        for name in OPTIONAL_ARRAYS:
            if getattr(self, name) is None:
                continue
            arr = np.asarray(getattr(self, name), dtype=float)
            if arr.shape != (n, 3):
                raise DataError(f"dataset: {name} has shape {arr.shape}, expected {(n, 3)}")
            object.__setattr__(self, name, arr)
        for name in OPTIONAL_SCALARS:
            if getattr(self, name) is None:
                continue
            arr = np.asarray(getattr(self, name), dtype=float)
            if arr.shape != (n,):
                raise DataError(f"dataset: {name} has shape {arr.shape}, expected {(n,)}")
            object.__setattr__(self, name, arr)
        meta = dict(self.meta)
        meta.setdefault("flights", [])
        if n and self.flight_id.min() < 0:
            raise DataError("dataset: flight_id must be non-negative")
        if n and (self.flight_id.min() < 0 or self.flight_id.max() >= len(meta["flights"])):
            meta["flights"] = _fill_flights(meta["flights"], self.flight_id, self.t_s)
        meta["n_samples"] = int(n)
        meta["minutes"] = _minutes(self.flight_id, meta["flights"])
        object.__setattr__(self, "meta", meta)

    def __len__(self) -> int:
        return int(self.x.shape[0])

    @property
    def n(self) -> int:
        """Number of samples."""
        return len(self)

    @property
    def minutes(self) -> float:
        """Flight time the samples span, minutes (samples x each flight's time step)."""
        return float(self.meta["minutes"])

    @property
    def n_flights(self) -> int:
        """Number of flights with at least one sample."""
        return int(len(np.unique(self.flight_id)))

    @property
    def flight_names(self) -> list[str]:
        """Names of the flights (indexed by ``flight_id``)."""
        return [str(f.get("name", f"flight{i}")) for i, f in enumerate(self.meta["flights"])]

    def interaction_mask(self, lateral_radius_m: float = INTERACTION_RADIUS_M) -> np.ndarray:
        """Boolean (n,): follower below the leader (``dp_z > 0``) within ``lateral_radius_m``."""
        dp = self.x[:, 0:3]
        return (dp[:, 2] > 0.0) & (np.hypot(dp[:, 0], dp[:, 1]) <= lateral_radius_m)

    def subset(self, index: np.ndarray) -> Dataset:
        """Samples ``index`` (integer indices or boolean mask) as a new Dataset.

        Flight ids are renumbered to the flights that remain; ``meta`` follows.
        """
        index = np.asarray(index)
        if index.dtype == bool:
            index = np.flatnonzero(index)
        fid = self.flight_id[index]
        kept, new_fid = np.unique(fid, return_inverse=True)
        flights = self.meta["flights"]
        meta = {**self.meta, "flights": [dict(flights[int(k)]) for k in kept]}
        for fmeta, k in zip(meta["flights"], kept, strict=True):
            fmeta["n_samples_used"] = int(np.sum(fid == k))
        return Dataset(
            x=self.x[index], leader_R=self.leader_R[index], y=self.y[index],
            flight_id=new_fid.reshape(-1), t_s=self.t_s[index], meta=meta,
            **{name: None if getattr(self, name) is None else getattr(self, name)[index]
               for name in OPTIONAL_ARRAYS + OPTIONAL_SCALARS},
        )

    def follower_diagonals_m(self) -> np.ndarray:
        """(n,) each sample's follower motor-to-motor diagonal (m) from its flight's metadata
        (``follower_diagonal_m``), NaN where the flight does not say."""
        out = np.full(self.n, np.nan)
        for k in np.unique(self.flight_id):
            value = self.meta["flights"][int(k)].get("follower_diagonal_m")
            if isinstance(value, int | float) and not isinstance(value, bool):
                out[self.flight_id == k] = float(value)
        return out

    def wake_scales(self, *, air_density_kgpm3: float = AIR_DENSITY_KGPM3,
                    gravity_mps2: float = GRAVITY_MPS2) -> np.ndarray:
        """The leader-aware kinds' wake scales (n, 4) (:data:`features.WAKE_SCALE_NAMES`).

        The leader's thrust is its logged (or commanded) thrust where the flight has one
        (:attr:`leader_thrust_n`), otherwise its hover thrust ``m g``; its rotor radius and
        count, and the follower's mass, rotor radius and count, come from the flight's
        metadata (``meta["flights"][k]``, from the FlightLog's ``meta``).

        Raises:
            DataError: a flight whose metadata lack one of these (one line naming it).
        """
        out = np.empty((self.n, len(WAKE_SCALE_NAMES)))
        thrust = (np.full(self.n, np.nan) if self.leader_thrust_n is None
                  else self.leader_thrust_n)
        for k in np.unique(self.flight_id):
            flight = self.meta["flights"][int(k)]
            keys = ("leader_mass_kg", "leader_rotor_radius_m", "leader_n_rotors",
                    "follower_mass_kg", "follower_rotor_radius_m", "follower_n_rotors")
            vals = {key: flight.get(key) for key in keys}
            missing = [key for key, v in vals.items() if v is None]
            if missing:
                raise DataError(f"dataset: flight {self.flight_names[int(k)]} does not say its "
                                f"{', '.join(missing)} (a leader-aware model needs them; for "
                                "Neural-Swarm logs ingest with --vehicle)")
            rows = self.flight_id == k
            hover_n = float(vals["leader_mass_kg"]) * gravity_mps2
            lead = np.where(np.isfinite(thrust[rows]) & (thrust[rows] > 0), thrust[rows], hover_n)
            out[rows] = wake_scales(
                lead, vals["leader_rotor_radius_m"], vals["leader_n_rotors"],
                vals["follower_mass_kg"], vals["follower_rotor_radius_m"],
                vals["follower_n_rotors"], air_density_kgpm3=air_density_kgpm3,
                gravity_mps2=gravity_mps2)
        return out

    def torque_labels(self) -> np.ndarray:
        """The torque labels (n, 3), N m, world NED, every sample having one.

        Raises:
            DataError: no torque labels, or flights without them (one line naming one).
        """
        if self.y_torque is None:
            raise DataError("dataset: no torque labels (the flight logs lack extra "
                            "'follower_obs_torque_nm' and 'follower_rotor_torque_nm')")
        missing = ~np.all(np.isfinite(self.y_torque), axis=1)
        if missing.any():
            name = self.flight_names[int(self.flight_id[np.argmax(missing)])]
            raise DataError(f"dataset: flight {name} has no torque labels (its log lacks extra "
                            "'follower_obs_torque_nm' or 'follower_rotor_torque_nm')")
        return self.y_torque

    def summary(self) -> dict[str, Any]:
        """Short JSON-ready description (what model files record about their training data)."""
        return {
            "n_samples": self.n,
            "n_flights": self.n_flights,
            "minutes": round(self.minutes, 4),
            "flights": self.flight_names,
            "sources": self.meta.get("sources", []),
            "has_true_mean": self.y_true_mean is not None,
            "has_torque": self.y_torque is not None,
            "label_bases": sorted({str(f["label_basis"]) for f in self.meta["flights"]
                                   if f.get("label_basis")}),
            "vehicles": vehicles_from_flights(self.meta["flights"]),
        }


def _fill_flights(flights: list[dict], flight_id: np.ndarray, t_s: np.ndarray) -> list[dict]:
    flights = [dict(f) for f in flights]
    for k in range(len(flights), int(flight_id.max()) + 1):
        t = t_s[flight_id == k]
        flights.append({"name": f"flight{k}", "n_samples": int(len(t)), "dt_s": _dt(t)})
    return flights


def _dt(t_s: np.ndarray) -> float:
    d = np.diff(np.sort(t_s))
    d = d[d > 0]
    return float(np.median(d)) if len(d) else 0.0


def _minutes(flight_id: np.ndarray, flights: list[dict]) -> float:
    counts = np.bincount(flight_id, minlength=len(flights)) if len(flight_id) else []
    return float(sum(c * float(f.get("dt_s", 0.0)) for c, f in zip(counts, flights)) / 60.0)


def _source(log: FlightLog) -> str:
    return str(log.meta.get("source", "unknown"))


@dataclass(frozen=True, eq=False)
class _FlightSamples:
    """One flight's valid samples, as the arrays a Dataset joins, and its ``meta["flights"]`` entry.

    The optional arrays are None when no flight of the data set has them (then no flight's
    arrays are joined); a flight without them among flights with them has NaN rows.
    """

    x: np.ndarray
    leader_R: np.ndarray
    y: np.ndarray
    flight_id: np.ndarray
    t_s: np.ndarray
    meta: dict[str, Any]
    y_true_mean: np.ndarray | None
    y_torque: np.ndarray | None
    y_torque_true: np.ndarray | None
    leader_thrust_n: np.ndarray | None = None


def _radii_used(logs: Sequence[FlightLog], free_air_radius_m: float | None) -> float | list[float]:
    """The free-air radius the labels used, m: one number, or each distinct one sorted."""
    radii = sorted({free_air_radius_of(log, free_air_radius_m) for log in logs})
    return radii[0] if len(radii) == 1 else radii


def build_dataset(
    logs: Sequence[FlightLog],
    *,
    free_air_radius_m: float | None = None,
    lowpass_hz: float | None = None,
) -> Dataset:
    """Labels and model inputs for a list of flights (biases estimated together).

    Args:
        logs: flights (time-aligned FlightLogs).
        free_air_radius_m: free-air radius for the bias estimate, m (None: each flight's own,
            else the default; see :func:`aerodock.learning.labels.free_air_radius_of`).
        lowpass_hz: optional low-pass cut-off for the labels (off by default).

    Raises:
        DataError: no flights, or no valid samples.
    """
    logs = list(logs)
    if not logs:
        raise DataError("dataset: no flights given")
    labels, biases, notes = labels_from_logs(
        logs, free_air_radius_m=free_air_radius_m, lowpass_hz=lowpass_hz
    )
    torque_logs = [log for log in logs if has_torque(log)]
    torque_labels, torque_biases, torque_notes = torque_labels_from_logs(
        torque_logs, free_air_radius_m=free_air_radius_m, lowpass_hz=lowpass_hz
    ) if torque_logs else ([], [], [])
    notes = notes + [f"torque labels: {note}" for note in torque_notes]
    torque_of = {id(log): (lab, bias) for log, lab, bias
                 in zip(torque_logs, torque_labels, torque_biases, strict=True)}
    any_true = any(TRUE_FIELD_KEY in log.extra for log in logs)
    any_thrust = any(LEADER_THRUST_KEY in log.extra for log in logs)
    flights = [
        _flight_samples(i, log, lab, bias, with_true=any_true, with_torque=bool(torque_logs),
                        torque=torque_of.get(id(log)), with_leader_thrust=any_thrust)
        for i, (log, lab, bias) in enumerate(zip(logs, labels, biases, strict=True))
    ]
    if not sum(len(f.flight_id) for f in flights):
        raise DataError("dataset: no valid samples in the given flights")
    meta = {
        "flights": [f.meta for f in flights],
        "sources": sorted({_source(log) for log in logs}),
        "labels": {
            "definition": "a_obs - u_1:3 - per-flight free-air median bias",
            "units": "m/s^2 NED",
            "free_air_radius_m": _radii_used(logs, free_air_radius_m),
            "lowpass_hz": lowpass_hz,
            **({"torque_definition": "obs_torque - rotor_torque - per-flight free-air median "
                                     "bias, rotated to the world frame",
                "torque_units": "N m NED"} if torque_logs else {}),
        },
        "warnings": notes,
    }
    return _join_flights(flights, meta)


def _flight_samples(i: int, log: FlightLog, labels: np.ndarray, bias: BiasEstimate, *,
                    with_true: bool, with_torque: bool,
                    torque: tuple[np.ndarray, BiasEstimate] | None,
                    with_leader_thrust: bool = False) -> _FlightSamples:
    """Flight ``i``'s valid samples: inputs, attitudes, labels and, if ``with_true`` or
    ``with_torque``, the true field and the torque arrays (NaN rows where it has none)."""
    keep = valid_mask(log)
    dp = log.follower_pos_m - log.leader_pos_m
    x = np.concatenate([dp, log.leader_vel_mps, log.follower_vel_mps], axis=1)
    y_true_mean = None
    if with_true:
        true = log.extra.get(TRUE_FIELD_KEY)
        if true is None:
            true = np.full((log.n_samples, 3), np.nan)
        true = np.asarray(true, dtype=float)
        if true.shape != (log.n_samples, 3):
            raise DataError(
                f"{log.name}: extra {TRUE_FIELD_KEY!r} has shape {true.shape}, "
                f"expected {(log.n_samples, 3)}"
            )
        y_true_mean = true[keep]
    leader_thrust = None
    if with_leader_thrust:
        raw = log.extra.get(LEADER_THRUST_KEY)
        raw = np.full(log.n_samples, np.nan) if raw is None else np.asarray(raw, float)
        if raw.shape != (log.n_samples,):
            raise DataError(f"{log.name}: extra {LEADER_THRUST_KEY!r} has shape {raw.shape}, "
                            f"expected {(log.n_samples,)}")
        leader_thrust = raw[keep]
    y_torque = y_torque_true = None
    torque_fields: dict[str, Any] = {}
    if with_torque:
        tau, tau_true, torque_bias = _torque_parts(log, torque)
        y_torque, y_torque_true = tau[keep], tau_true[keep]
        if torque_bias is not None:
            torque_fields = {"torque_bias_nm": [float(b) for b in torque_bias.bias],
                             "torque_bias_source": torque_bias.source}
    meta = {
        "name": log.name,
        "source": _source(log),
        "n_samples": int(keep.sum()),
        "duration_s": round(log.duration_s, 6),
        "dt_s": _dt(log.t_s),
        "bias_mps2": [float(b) for b in bias.bias_mps2],
        "bias_source": bias.source,
        "n_free_air": bias.n_free_air,
        "label_basis": log.meta.get("label_basis"),
        **torque_fields,
        **flight_vehicle_fields(log.meta),
    }
    return _FlightSamples(
        x=x[keep], leader_R=quat_to_rotmat(log.leader_quat)[keep], y=labels[keep],
        flight_id=np.full(int(keep.sum()), i, dtype=np.int64), t_s=log.t_s[keep], meta=meta,
        y_true_mean=y_true_mean, y_torque=y_torque, y_torque_true=y_torque_true,
        leader_thrust_n=leader_thrust,
    )


def _join_flights(flights: list[_FlightSamples], meta: dict[str, Any]) -> Dataset:
    """The flights' samples as one Dataset; a true torque that is NaN throughout is dropped."""
    first = flights[0]

    def joined(name: str) -> np.ndarray | None:
        """The flights' optional array ``name`` joined, or None if they do not have it."""
        if getattr(first, name) is None:
            return None
        return np.concatenate([getattr(f, name) for f in flights])

    tau_true = joined("y_torque_true")
    return Dataset(
        x=np.concatenate([f.x for f in flights]),
        leader_R=np.concatenate([f.leader_R for f in flights]),
        y=np.concatenate([f.y for f in flights]),
        flight_id=np.concatenate([f.flight_id for f in flights]),
        t_s=np.concatenate([f.t_s for f in flights]),
        y_true_mean=joined("y_true_mean"),
        meta=meta,
        y_torque=joined("y_torque"),
        y_torque_true=tau_true if tau_true is not None and np.isfinite(tau_true).any() else None,
        leader_thrust_n=joined("leader_thrust_n"),
    )


def _torque_parts(log: FlightLog, labelled: tuple[np.ndarray, BiasEstimate] | None
                  ) -> tuple[np.ndarray, np.ndarray, BiasEstimate | None]:
    """A flight's torque labels and true wake torque (T, 3), world NED (NaN where it has none),
    and its torque bias (None without labels)."""
    nan = np.full((log.n_samples, 3), np.nan)
    rot = quat_to_rotmat(log.follower_quat)
    true = log.extra.get(TRUE_TORQUE_KEY)
    if true is not None:
        true = np.asarray(true, dtype=float)
        if true.shape != (log.n_samples, 3):
            raise DataError(f"{log.name}: extra {TRUE_TORQUE_KEY!r} has shape {true.shape}, "
                            f"expected {(log.n_samples, 3)}")
        true = np.einsum("nij,nj->ni", rot, true)
    if labelled is None:
        return nan, nan if true is None else true, None
    labels_body, bias = labelled
    return (np.einsum("nij,nj->ni", rot, labels_body), nan if true is None else true, bias)


def concat_datasets(datasets: Sequence[Dataset]) -> Dataset:
    """Concatenate datasets (flight ids offset; metadata merged)."""
    datasets = list(datasets)
    if not datasets:
        raise DataError("dataset: nothing to concatenate")
    if len(datasets) == 1:
        return datasets[0]
    flights: list[dict] = []
    fids = []
    for d in datasets:
        fids.append(d.flight_id + len(flights))
        flights.extend(dict(f) for f in d.meta["flights"])
    optional = {}
    for name in OPTIONAL_ARRAYS:
        if any(getattr(d, name) is not None for d in datasets):
            optional[name] = np.concatenate([
                getattr(d, name) if getattr(d, name) is not None else np.full((d.n, 3), np.nan)
                for d in datasets])
    for name in OPTIONAL_SCALARS:
        if any(getattr(d, name) is not None for d in datasets):
            optional[name] = np.concatenate([
                getattr(d, name) if getattr(d, name) is not None else np.full(d.n, np.nan)
                for d in datasets])
    meta = {
        "flights": flights,
        "sources": sorted({s for d in datasets for s in d.meta.get("sources", [])}),
        "labels": [d.meta.get("labels") for d in datasets],
        "warnings": [w for d in datasets for w in d.meta.get("warnings", [])],
    }
    return Dataset(
        x=np.concatenate([d.x for d in datasets]),
        leader_R=np.concatenate([d.leader_R for d in datasets]),
        y=np.concatenate([d.y for d in datasets]),
        flight_id=np.concatenate(fids),
        t_s=np.concatenate([d.t_s for d in datasets]),
        meta=meta, **optional,
    )
