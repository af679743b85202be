"""Model files: a directory with ``weights.npz`` (plain float arrays) and ``model.json``.

Safe by construction: weights are read with ``np.load(allow_pickle=False)`` and metadata with
``json``; nothing is ever unpickled, so a model file from an untrusted source cannot run code.
NumPy-only (the runtime uses it without PyTorch).

``model.json`` holds: ``format`` (``"aerodock-model"``), ``version``, ``kind`` (``so2``,
``so2-ext``, ``so2-wrench``, ``mlp``, ``zero``), ``feature_version``, ``units`` (``"m/s^2 NED"``,
the force's; a ``so2-wrench`` model also has ``torque_units``, ``"N m NED"``), the feature
regularisation constants, ``layer_sizes`` ``[F, hidden..., K]``, ``activation``,
``spectral_norm``, ``normalisation`` (``in_mean``/``in_std`` of the F features, ``out_mean``/
``out_std`` of the K outputs), ``weights`` (file name, SHA-256, array names), ``training`` (data
summary, seed, epochs, validation loss, training time, ...) and ``aerodock_version``.

``weights.npz`` holds ``W0, b0, W1, b1, ...``: ``W{i}`` has shape ``(layer_sizes[i+1],
layer_sizes[i])`` (torch's ``Linear`` layout) and ``b{i}`` ``(layer_sizes[i+1],)``. The network
computes ``c = (L_last o act o ... o act o L_0)((z - in_mean) / in_std) * out_std + out_mean``.

``model.json`` also records ``vehicles``: the leader's and the follower's mass, rotor radius and
rotor count of the flights it was trained on (``None`` where the logs did not say), so that a
model flown on other vehicles can be flagged (:func:`vehicle_mismatches`).

The directory is written as a whole: both files go into a fresh sibling directory, which then
takes the old one's place by an atomic exchange of the two names (``renameat2`` with
``RENAME_EXCHANGE`` on Linux; elsewhere two renames, undone on failure). A kill at any moment
leaves either the complete old model or the complete new one, never a mix, and a failed save
leaves no temporary directory behind. The SHA-256 of ``weights.npz`` in ``model.json`` is
required on load: it detects a weights file that does not belong to it.
"""

from __future__ import annotations

import ctypes
import datetime as _dt
import hashlib
import io
import json
import math
import os
import shutil
import tempfile
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from aerodock.fileio import READ_ERRORS, check_npz_sizes
from aerodock.learning.features import (
    EPS_POS_M,
    EPS_VEL_MPS,
    FEATURE_NAMES,
    FEATURE_VERSION,
    KINDS,
    N_FEATURES,
    N_OUTPUTS,
    OUTPUT_NAMES,
    TORQUE_KINDS,
)

MODEL_FORMAT = "aerodock-model"
MODEL_VERSION = 1
MODEL_JSON = "model.json"
WEIGHTS_NPZ = "weights.npz"
ACTIVATIONS = ("tanh", "silu")
UNITS = "m/s^2 NED"
TORQUE_UNITS = "N m NED"
VEHICLE_KEYS = ("mass_kg", "rotor_radius_m", "n_rotors")
# Relative difference of a vehicle parameter above which a model is flagged as trained on
# other vehicles (the wake scales with the thrust, i.e. the mass, and the rotor disc area).
VEHICLE_TOLERANCE = 0.1


class ModelFileError(ValueError):
    """A model directory is missing, corrupt or does not match this aerodock; one-line message."""


@dataclass(frozen=True)
class ModelSpec:
    """Everything needed to rebuild a model's computation (besides the weights).

    Attributes:
        kind: ``"so2"``, ``"so2-ext"``, ``"so2-wrench"``, ``"mlp"`` or ``"zero"``.
        layer_sizes: ``(F, hidden..., K)``; empty for ``"zero"``.
        activation: hidden-layer activation, ``"tanh"`` or ``"silu"``.
        in_mean: (F,) feature means.
        in_std: (F,) feature scales.
        out_mean: (K,) output offsets.
        out_std: (K,) output scales.
        spectral_norm: whether training used spectral normalisation (weights are stored
            already normalised).
        eps_pos_m: feature regularisation (see :mod:`aerodock.learning.features`).
        eps_vel_mps: feature regularisation.
        feature_version: version of the feature definitions.
    """

    kind: str
    layer_sizes: tuple[int, ...] = ()
    activation: str = "tanh"
    in_mean: np.ndarray = field(default_factory=lambda: np.zeros(0))
    in_std: np.ndarray = field(default_factory=lambda: np.ones(0))
    out_mean: np.ndarray = field(default_factory=lambda: np.zeros(0))
    out_std: np.ndarray = field(default_factory=lambda: np.ones(0))
    spectral_norm: bool = False
    eps_pos_m: float = EPS_POS_M
    eps_vel_mps: float = EPS_VEL_MPS
    feature_version: int = FEATURE_VERSION

    def weight_shapes(self) -> list[tuple[tuple[int, int], tuple[int]]]:
        """Expected ``(W shape, b shape)`` per layer."""
        s = self.layer_sizes
        return [((s[i + 1], s[i]), (s[i + 1],)) for i in range(len(s) - 1)]


def _aerodock_version() -> str:
    try:
        from importlib.metadata import version

        return version("aerodock")
    except Exception:  # not installed: running from a source tree
        return "unknown"


def _f32_list(a: np.ndarray) -> list[float]:
    """Values rounded to float32 (what the torch model uses) as exact JSON floats."""
    return [float(v) for v in np.asarray(a, dtype=np.float32)]


def save_model_dir(
    path: str | Path,
    spec: ModelSpec,
    weights: list[tuple[np.ndarray, np.ndarray]],
    *,
    training: dict[str, Any] | None = None,
    vehicles: dict[str, Any] | None = None,
) -> Path:
    """Write a model directory atomically (see the module docstring); returns its path.

    Args:
        path: the directory. An existing one is replaced as a whole; it must be a model
            directory (only ``model.json`` and ``weights.npz``) or empty.
        spec: the model's spec.
        weights: ``[(W0, b0), (W1, b1), ...]`` in torch's ``Linear`` layout.
        training: JSON-ready training summary recorded in ``model.json``.
        vehicles: ``{"leader": {...}, "follower": {...}}`` with :data:`VEHICLE_KEYS`; default:
            ``training["data"]["vehicles"]`` (what the training data's flights said).

    Raises:
        ValueError: weights that do not match ``spec``, or a ``path`` that is not a model
            directory.
        OSError: the directory cannot be written (the old model is left as it was).
    """
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise ValueError(f"{path}: exists and is not a directory")
    if path.is_dir():
        others = sorted(p.name for p in path.iterdir() if p.name not in (MODEL_JSON, WEIGHTS_NPZ))
        if others:
            raise ValueError(f"{path}: holds files that are not part of a model "
                             f"({', '.join(others[:3])}); not replaced")
    expected = spec.weight_shapes()
    if len(weights) != len(expected) or any(
        np.shape(w) != ws or np.shape(b) != bs for (w, b), (ws, bs) in zip(weights, expected)
    ):
        raise ValueError(f"weights do not match layer sizes {list(spec.layer_sizes)}")
    if vehicles is None:
        data = (training or {}).get("data")
        vehicles = data.get("vehicles") if isinstance(data, Mapping) else None
    doc: dict[str, Any] = {
        "format": MODEL_FORMAT,
        "version": MODEL_VERSION,
        "kind": spec.kind,
        "feature_version": spec.feature_version,
        "units": UNITS,
        "input": "x (n, 9) = [dp = p_follower - p_leader, v_leader, v_follower] (m, m/s, NED); "
                 "leader_R (n, 3, 3) leader attitude, body to world",
        "output": "f_ext (n, 3): predicted downwash acceleration on the follower, m/s^2, NED"
                  + ("; tau_ext (n, 3): predicted wake torque on the follower about its centre "
                     "of mass, N m, world NED" if spec.kind in TORQUE_KINDS else ""),
        **({"torque_units": TORQUE_UNITS} if spec.kind in TORQUE_KINDS else {}),
        "vehicles": normalise_vehicles(vehicles),
        "features": {
            "names": list(FEATURE_NAMES[spec.kind]),
            "eps_pos_m": spec.eps_pos_m,
            "eps_vel_mps": spec.eps_vel_mps,
        },
        "outputs": list(OUTPUT_NAMES[spec.kind]),
        "layer_sizes": [int(s) for s in spec.layer_sizes],
        "activation": spec.activation,
        "spectral_norm": bool(spec.spectral_norm),
        "normalisation": {
            "in_mean": _f32_list(spec.in_mean), "in_std": _f32_list(spec.in_std),
            "out_mean": _f32_list(spec.out_mean), "out_std": _f32_list(spec.out_std),
        },
        "training": training or {},
        "aerodock_version": _aerodock_version(),
        "created_utc": _dt.datetime.now(_dt.UTC).strftime("%Y-%m-%dT%H:%M:%SZ"),
    }
    files: dict[str, bytes] = {}
    if expected:
        arrays = {}
        for i, (w, b) in enumerate(weights):
            arrays[f"W{i}"] = np.asarray(w, dtype=np.float32)
            arrays[f"b{i}"] = np.asarray(b, dtype=np.float32)
        buf = io.BytesIO()
        np.savez(buf, **arrays)
        files[WEIGHTS_NPZ] = buf.getvalue()
        doc["weights"] = {
            "file": WEIGHTS_NPZ, "sha256": hashlib.sha256(files[WEIGHTS_NPZ]).hexdigest(),
            "arrays": sorted(arrays), "dtype": "float32",
        }
    else:
        doc["weights"] = None
    files[MODEL_JSON] = (json.dumps(doc, indent=2) + "\n").encode()
    write_dir_atomic(path, files)
    return path


# --------------------------------------------------------------------------------------------
# Writing a directory as a whole
# --------------------------------------------------------------------------------------------

_RENAME_EXCHANGE = 2
_AT_FDCWD = -100


def _exchange(a: Path, b: Path) -> bool:
    """Swap two existing paths in one atomic step (Linux ``renameat2``); False if unsupported."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        renameat2 = libc.renameat2
    except (OSError, AttributeError):
        return False
    renameat2.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p,
                          ctypes.c_uint]
    if renameat2(_AT_FDCWD, os.fsencode(a), _AT_FDCWD, os.fsencode(b), _RENAME_EXCHANGE) == 0:
        return True
    errno = ctypes.get_errno()
    if errno in (22, 38, 95):  # EINVAL, ENOSYS, EOPNOTSUPP: file system or kernel cannot
        return False
    raise OSError(errno, f"cannot exchange {a} and {b}: {os.strerror(errno)}")


def _fsync_dir(path: Path) -> None:
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def write_dir_atomic(path: str | Path, files: Mapping[str, bytes]) -> Path:
    """Make ``path`` a directory holding exactly ``files`` (name -> bytes), all at once.

    The files are written and synced in a sibling temporary directory that then swaps names
    with ``path`` atomically (or is renamed to it if ``path`` does not exist). Where the atomic
    exchange is unsupported, the old directory is renamed aside first and restored if the
    second rename fails. On any error the temporary directory is removed and ``path`` is left
    as it was.

    Raises:
        OSError: the files cannot be written.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp"))
    try:
        os.chmod(tmp, 0o777 & ~_umask())
        for name, blob in files.items():
            with open(tmp / name, "wb") as fh:
                fh.write(blob)
                fh.flush()
                os.fsync(fh.fileno())
        _fsync_dir(tmp)
        if not path.exists():
            os.rename(tmp, path)
        elif _exchange(tmp, path):
            shutil.rmtree(tmp)  # now holds the old model
        else:
            aside = Path(tempfile.mkdtemp(dir=path.parent, prefix=f".{path.name}.", suffix=".old"))
            os.rmdir(aside)
            os.rename(path, aside)
            try:
                os.rename(tmp, path)
            except BaseException:
                os.rename(aside, path)
                raise
            shutil.rmtree(aside, ignore_errors=True)
        _fsync_dir(path.parent)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return path


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


# --------------------------------------------------------------------------------------------
# The vehicles a model was trained on
# --------------------------------------------------------------------------------------------


def _number(value: Any) -> float | None:
    try:
        out = float(value)
    except (TypeError, ValueError):
        return None
    return out if math.isfinite(out) and out > 0 else None


def normalise_vehicles(vehicles: Mapping[str, Any] | None) -> dict[str, dict[str, Any]]:
    """``{"leader": {mass_kg, rotor_radius_m, n_rotors}, "follower": {...}}``, None if unknown.

    A value that is not a positive finite number (or a list of them, when the training flights
    disagree) becomes ``None``.
    """
    out: dict[str, dict[str, Any]] = {}
    for role in ("leader", "follower"):
        given = vehicles.get(role) if isinstance(vehicles, Mapping) else None
        given = given if isinstance(given, Mapping) else {}
        entry: dict[str, Any] = {}
        for key in VEHICLE_KEYS:
            value = given.get(key)
            if isinstance(value, list | tuple):
                values = [_number(v) for v in value]
                entry[key] = values if values and all(v is not None for v in values) else None
            else:
                entry[key] = _number(value)
            if key == "n_rotors" and entry[key] is not None:
                entry[key] = ([int(v) for v in entry[key]] if isinstance(entry[key], list)
                              else int(entry[key]))
        out[role] = entry
    return out


def flight_vehicle_fields(meta: Mapping[str, Any]) -> dict[str, float | None]:
    """A FlightLog ``meta``'s ``{leader,follower}_{mass_kg,rotor_radius_m,n_rotors}`` (or None)."""
    return {f"{role}_{key}": _number(meta.get(f"{role}_{key}"))
            for role in ("leader", "follower") for key in VEHICLE_KEYS}


def vehicles_from_flights(flights: Iterable[Mapping[str, Any]]) -> dict[str, dict[str, Any]]:
    """The vehicles of training flights (their ``leader_mass_kg``, ``follower_rotor_radius_m``...).

    A parameter that every flight gives with one value is that value; one that differs between
    flights is the sorted list of values; one that any flight lacks is ``None``.
    """
    flights = list(flights)
    out: dict[str, dict[str, Any]] = {}
    for role in ("leader", "follower"):
        entry: dict[str, Any] = {}
        for key in VEHICLE_KEYS:
            values = [_number(f.get(f"{role}_{key}")) for f in flights]
            if not values or any(v is None for v in values):
                entry[key] = None
                continue
            unique = sorted(set(values))
            entry[key] = unique[0] if len(unique) == 1 else unique
        out[role] = entry
    return normalise_vehicles(out)


def configured_vehicles(cfg: Any) -> dict[str, dict[str, Any]]:
    """The vehicles of an aerodock config (``[vehicle]``: both quadrotors are alike)."""
    vehicle = cfg.vehicle
    one = {"mass_kg": vehicle.mass_kg, "rotor_radius_m": vehicle.rotor_radius_m,
           "n_rotors": vehicle.n_rotors}
    return normalise_vehicles({"leader": one, "follower": one})


def vehicle_mismatches(model_vehicles: Mapping[str, Any] | None,
                       configured: Mapping[str, Any]) -> list[str]:
    """One-line notes where a model's training vehicles differ from the configured ones.

    A mass or rotor radius more than :data:`VEHICLE_TOLERANCE` (relative) off, or another rotor
    count, is noted. A model that records none of them (saved before aerodock recorded them)
    gets one note saying so; parameters some logs do not carry (simulated logs record masses
    only) are compared where known.
    """
    model = normalise_vehicles(model_vehicles)
    config = normalise_vehicles(configured)
    notes: list[str] = []
    unknown: list[str] = []
    for role in ("leader", "follower"):
        for key in VEHICLE_KEYS:
            have, want = model[role][key], config[role][key]
            if want is None:
                continue
            if have is None:
                unknown.append(f"{role} {key}")
                continue
            values = have if isinstance(have, list) else [have]
            if key == "n_rotors":
                off = any(int(v) != int(want) for v in values)
            else:
                off = any(abs(v - want) > VEHICLE_TOLERANCE * want for v in values)
            if off:
                shown = "/".join(f"{v:g}" for v in values)
                notes.append(f"model trained with {role} {key} = {shown}, configured {want:g}")
    known = sum(model[role][key] is not None for role in model for key in VEHICLE_KEYS)
    if unknown and not known:
        notes.append("model does not record the vehicles it was trained on (saved before "
                     "aerodock recorded them, or trained on logs without masses)")
    return notes


def model_vehicle_warnings(predictor_or_doc: Any, cfg: Any) -> list[str]:
    """Warnings for running a model (a Predictor or a ``model.json`` dict) on ``cfg``'s vehicles.

    The ``dock`` command and the ROS node print these; an empty list means the vehicles match.
    """
    doc = getattr(predictor_or_doc, "meta", predictor_or_doc)
    if not isinstance(doc, Mapping) or doc.get("kind") == "zero":
        return []  # the zero model predicts nothing, whatever the vehicles
    return vehicle_mismatches(doc.get("vehicles"), configured_vehicles(cfg))


def model_pairing_warnings(predictor_or_doc: Any, cfg: Any) -> list[str]:
    """Warnings for flying a model with ``cfg``'s torque feed-forward when its force labels were
    made on the paper's command basis (``a_obs - u_1:3``): such a model already counts the tilt
    the wake's torque causes as force, and cancelling the torque as well holds the follower off
    the wake's axis (README, *Label basis*). Models that do not record their labels' basis pass.
    """
    doc = getattr(predictor_or_doc, "meta", predictor_or_doc)
    control = getattr(cfg, "control", None)
    if not isinstance(doc, Mapping) or not getattr(control, "torque_feedforward", False):
        return []
    data = doc.get("training", {}).get("data", {}) if isinstance(doc.get("training"),
                                                                   Mapping) else {}
    bases = data.get("label_bases") if isinstance(data, Mapping) else None
    if isinstance(bases, list) and "command" in bases:
        return ["the model's force labels are on the command basis (a_obs - u_1:3, which counts "
                "the tilt the wake's torque causes); with control.torque_feedforward that torque "
                "is compensated twice: train on curriculum.label_basis = \"thrust\" flights"]
    return []


def model_warnings(predictor_or_doc: Any, cfg: Any) -> list[str]:
    """Every warning for flying a model on ``cfg``: other vehicles
    (:func:`model_vehicle_warnings`) and a torque feed-forward its labels do not suit
    (:func:`model_pairing_warnings`). ``dock``, ``targets`` and the ROS node print these."""
    return model_vehicle_warnings(predictor_or_doc, cfg) + model_pairing_warnings(
        predictor_or_doc, cfg)


def _floats(doc: dict, key: str, n: int, where: Path) -> np.ndarray:
    try:
        arr = np.asarray(doc[key], dtype=float)
    except (KeyError, TypeError, ValueError):
        raise ModelFileError(f"{where}: normalisation.{key} missing or not numbers") from None
    if arr.shape != (n,) or not np.all(np.isfinite(arr)):
        raise ModelFileError(f"{where}: normalisation.{key} must be {n} finite numbers")
    return arr


def load_model_dir(
    path: str | Path,
) -> tuple[ModelSpec, list[tuple[np.ndarray, np.ndarray]], dict[str, Any]]:
    """Read and check a model directory.

    Returns:
        ``(spec, weights, doc)``: the spec, ``[(W, b), ...]`` as float64 arrays, and the whole
        ``model.json`` document.

    Raises:
        ModelFileError: one line naming the file: missing, corrupt, wrong format or version,
            unknown kind or activation, feature version mismatch, shapes that do not match,
            non-finite values, or a weights file that does not belong to ``model.json``.
    """
    path = Path(path)
    if path.is_file() and path.name == MODEL_JSON:
        path = path.parent
    jpath = path / MODEL_JSON
    if not path.is_dir():
        raise ModelFileError(f"{path}: model directory not found")
    if not jpath.is_file():
        raise ModelFileError(f"{jpath}: not found (not an aerodock model directory)")
    try:
        doc = json.loads(jpath.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as err:
        raise ModelFileError(f"{jpath}: corrupt model.json ({err})") from None
    except RecursionError:
        raise ModelFileError(f"{jpath}: corrupt model.json (nested too deeply)") from None
    if not isinstance(doc, dict) or doc.get("format") != MODEL_FORMAT:
        raise ModelFileError(f"{jpath}: not an aerodock model file")
    version = doc.get("version")
    if not isinstance(version, int) or version < 1:
        raise ModelFileError(f"{jpath}: bad version {version!r}")
    if version > MODEL_VERSION:
        raise ModelFileError(
            f"{jpath}: model format version {version} is newer than this aerodock "
            f"({MODEL_VERSION}); upgrade aerodock"
        )
    kind = doc.get("kind")
    if kind not in KINDS:
        raise ModelFileError(f"{jpath}: unknown model kind {kind!r}")
    if doc.get("feature_version") != FEATURE_VERSION:
        raise ModelFileError(
            f"{jpath}: feature version {doc.get('feature_version')!r} does not match this "
            f"aerodock ({FEATURE_VERSION})"
        )
    if doc.get("units") != UNITS:
        raise ModelFileError(f"{jpath}: units {doc.get('units')!r}, expected {UNITS!r}")
    if kind in TORQUE_KINDS and doc.get("torque_units") != TORQUE_UNITS:
        raise ModelFileError(f"{jpath}: torque_units {doc.get('torque_units')!r}, expected "
                             f"{TORQUE_UNITS!r}")
    if kind == "zero":
        return ModelSpec(kind="zero"), [], doc
    sizes = doc.get("layer_sizes")
    if (not isinstance(sizes, list) or len(sizes) < 2
            or not all(isinstance(s, int) and s > 0 for s in sizes)):
        raise ModelFileError(f"{jpath}: layer_sizes must be a list of positive integers")
    if sizes[0] != N_FEATURES[kind] or sizes[-1] != N_OUTPUTS[kind]:
        raise ModelFileError(
            f"{jpath}: layer_sizes {sizes} do not fit kind {kind!r} "
            f"({N_FEATURES[kind]} features, {N_OUTPUTS[kind]} outputs)"
        )
    activation = doc.get("activation")
    if activation not in ACTIVATIONS:
        raise ModelFileError(f"{jpath}: unknown activation {activation!r}")
    norm = doc.get("normalisation")
    if not isinstance(norm, dict):
        raise ModelFileError(f"{jpath}: normalisation missing")
    feats = doc.get("features") or {}
    try:
        eps_pos = float(feats.get("eps_pos_m", EPS_POS_M))
        eps_vel = float(feats.get("eps_vel_mps", EPS_VEL_MPS))
    except (TypeError, ValueError, AttributeError):
        raise ModelFileError(f"{jpath}: features.eps_* must be numbers") from None
    if not (eps_pos > 0 and eps_vel > 0 and np.isfinite(eps_pos) and np.isfinite(eps_vel)):
        raise ModelFileError(f"{jpath}: features.eps_* must be positive")
    spec = ModelSpec(
        kind=kind, layer_sizes=tuple(sizes), activation=activation,
        in_mean=_floats(norm, "in_mean", sizes[0], jpath),
        in_std=_floats(norm, "in_std", sizes[0], jpath),
        out_mean=_floats(norm, "out_mean", sizes[-1], jpath),
        out_std=_floats(norm, "out_std", sizes[-1], jpath),
        spectral_norm=bool(doc.get("spectral_norm", False)),
        eps_pos_m=eps_pos, eps_vel_mps=eps_vel,
    )
    if np.any(spec.in_std <= 0):
        raise ModelFileError(f"{jpath}: normalisation.in_std must be positive")
    return spec, _load_weights(path, spec, doc), doc


def _load_weights(
    path: Path, spec: ModelSpec, doc: dict[str, Any]
) -> list[tuple[np.ndarray, np.ndarray]]:
    wpath = path / WEIGHTS_NPZ
    winfo = doc.get("weights")
    if not isinstance(winfo, dict):
        raise ModelFileError(f"{path / MODEL_JSON}: weights entry missing")
    try:
        blob = wpath.read_bytes()
    except FileNotFoundError:
        raise ModelFileError(f"{wpath}: not found") from None
    except OSError as err:
        raise ModelFileError(f"{wpath}: unreadable ({err})") from None
    sha = winfo.get("sha256")
    if not isinstance(sha, str) or len(sha) != 64:
        raise ModelFileError(
            f"{path / MODEL_JSON}: weights.sha256 missing or malformed: the weights cannot be "
            "verified (re-save the model with this aerodock)"
        )
    if hashlib.sha256(blob).hexdigest() != sha.lower():
        raise ModelFileError(
            f"{wpath}: does not match {MODEL_JSON} (SHA-256 differs): corrupt or mixed up"
        )
    weights = []
    try:
        with np.load(io.BytesIO(blob), allow_pickle=False) as data:
            # The sizes each array declares, before any is read (a corrupt header could
            # otherwise make NumPy allocate terabytes).
            check_npz_sizes(data, wpath, ModelFileError)
            for i, (wshape, bshape) in enumerate(spec.weight_shapes()):
                for name, shape in ((f"W{i}", wshape), (f"b{i}", bshape)):
                    if name not in data.files:
                        raise ModelFileError(f"{wpath}: array {name} missing")
                    arr = data[name]
                    if arr.shape != shape:
                        raise ModelFileError(
                            f"{wpath}: {name} has shape {arr.shape}, expected {shape}"
                        )
                    if arr.dtype.kind != "f" or not np.all(np.isfinite(arr)):
                        raise ModelFileError(f"{wpath}: {name} must hold finite floats")
                weights.append(
                    (data[f"W{i}"].astype(np.float64), data[f"b{i}"].astype(np.float64))
                )
    except ModelFileError:
        raise
    except READ_ERRORS as err:
        raise ModelFileError(f"{wpath}: corrupt weights file ({type(err).__name__}: "
                             f"{' '.join(str(err).split())})") from None
    return weights
