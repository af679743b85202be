"""Model files: a directory with ``weights.npz`` (plain float arrays) and ``model.json``.

Safe by construction: weights are read with ``np.load(allow_pickle=False)`` and metadata with
``json``; nothing is ever unpickled, so a model file from an untrusted source cannot run code.
NumPy-only (the runtime uses it without PyTorch).

``model.json`` holds: ``format`` (``"aerodock-model"``), ``version``, ``kind`` (a kind of
:mod:`aerodock.learning.kinds`: ``so2``, ``so2-ext``, ``so2-wrench``, ...), ``feature_version``,
``units`` (``"m/s^2 NED"``, the force's; a ``so2-wrench`` model also has ``torque_units``,
``"N m NED"``), the feature regularisation constants, ``layer_sizes`` ``[F, hidden..., K]``,
``activation``, ``spectral_norm``, ``normalisation`` (``in_mean``/``in_std`` of the F features,
``out_mean``/``out_std`` of the K outputs), ``weights`` (file name, SHA-256, array names),
``training`` (data summary with the flights' ``label_bases``, seed, epochs, validation loss,
training time, ...), ``aerodock_version``, ``created_utc`` and, last, ``model_sha256`` (the
document's own checksum).

``weights.npz`` holds ``W0, b0, W1, b1, ...``: ``W{i}`` has shape ``(layer_sizes[i+1],
layer_sizes[i])`` (torch's ``Linear`` layout) and ``b{i}`` ``(layer_sizes[i+1],)``; in a
deep-sets kind's network (``Kind.weight_shapes``), the first layer takes the neighbour's
features only and the first ``rho`` layer the ego features besides ``phi``'s output. The network
computes ``c = (L_last o act o ... o act o L_0)((z - in_mean) / in_std) * out_std + out_mean``.

``model.json`` also records ``vehicles``: the leader's and the follower's mass, rotor radius,
rotor count and motor-to-motor diagonal of the flights it was trained on (``None`` where the
logs did not say; see :mod:`aerodock.learning.training_vehicles`), so that a model flown on
other vehicles can be flagged (:mod:`aerodock.deploy.compatibility`) and a larger follower
predicted over its rotor footprint (:mod:`aerodock.learning.footprint`).

The directory is written as a whole (:func:`aerodock.fileio.write_dir_atomic`): a kill at any
moment leaves either the complete old model or the complete new one, never a mix, and a failed
save leaves no temporary directory behind (a kill's is removed by the next save in the folder).

Both files are checked whole on load (format version 2). ``weights.sha256`` is the SHA-256 of
``weights.npz``; ``model_sha256`` is the SHA-256 of ``model.json`` itself without that one key,
in a canonical form (:func:`model_checksum`: the parsed document written by Python's ``json``
with sorted keys, no spaces, ASCII only), so it covers everything a prediction depends on (kind,
features, layer sizes, activation, normalisation, the weights through their SHA-256) and
everything else the file says (units, vehicles, the training data's label bases, ...): any
change to the document is refused, whatever its layout (reindenting is not a change). It
detects damage and edits, not an adversary (anyone can recompute it). Version 1 files (before
the document had a checksum) still load, with only their weights verified;
:func:`upgrade_model_dir` re-saves one as version 2. The normalisation must also be plausible
(:func:`check_normalisation`), whatever the version.
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import io
import json
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from aerodock.fileio import (
    MAX_JSON_BYTES,
    MAX_NPZ_BYTES,
    READ_ERRORS,
    InputError,
    check_npz_sizes,
    read_input_bytes,
    read_input_text,
    write_dir_atomic,
)
from aerodock.learning.features import EPS_POS_M, EPS_VEL_MPS, FEATURE_VERSION
from aerodock.learning.kinds import REGISTRY, get_kind
from aerodock.learning.training_vehicles import normalise_vehicles

MODEL_FORMAT = "aerodock-model"
# 2: model.json carries model_sha256 (the document's own checksum); 1: only the weights' one.
MODEL_VERSION = 2
CHECKSUM_KEY = "model_sha256"
MODEL_JSON = "model.json"
WEIGHTS_NPZ = "weights.npz"
ACTIVATIONS = ("tanh", "silu")
UNITS = "m/s^2 NED"
TORQUE_UNITS = "N m NED"


# Plausibility limits of the normalisation, checked on save and on load (a model file is
# refused beyond them, whatever its checksum says). The features are metres, metres per second or
# cosines: a mean or a scale beyond 1e4 (two vehicles 10 km apart, or flying at 10 km/s) is no
# docking flight. The outputs are m/s^2 (force) or N m (torque): 1e3 m/s^2 is about 100 g, beyond
# any flight controller's accelerometer range (16-32 g) plus any commanded acceleration, and 1e3
# N m beyond the motors of any multirotor (the wake's torque on the paper's 0.7 kg vehicles is
# 0.03 N m RMS). A scale below 1e-6 (a micrometre, a micrometre per second, ...) is below any
# sensor's resolution; training floors its scales at 0.05 (features) and 1e-3 (outputs).
MAX_INPUT_SCALE = 1e4
MAX_OUTPUT_SCALE = 1e3
MIN_SCALE = 1e-6


class ModelFileError(ValueError):
    """A model directory is missing, corrupt or does not match this aerodock; one-line message."""


@dataclass(frozen=True)
class ModelSpec:
    """Everything needed to rebuild a model's computation (besides the weights).

    Attributes:
        kind: a kind of :mod:`aerodock.learning.kinds`.
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
        """Expected ``(W shape, b shape)`` per layer (the kind's network layout; a chain
        ``W{i}: (layer_sizes[i+1], layer_sizes[i])`` but for a deep-sets kind)."""
        return get_kind(self.kind).weight_shapes(self.layer_sizes)


def _aerodock_version() -> str:
    try:
        from importlib.metadata import version

        return version("aerodock")
    except Exception:  # not installed: running from a source tree
        return "unknown"


def _f32_list(a: np.ndarray) -> list[float]:
    """Values rounded to float32 (what the torch model uses) as exact JSON floats."""
    return [float(v) for v in np.asarray(a, dtype=np.float32)]


def model_checksum(doc: Mapping[str, Any]) -> str:
    """SHA-256 (hex) of a ``model.json`` document without its :data:`CHECKSUM_KEY`.

    The canonical form is the document written by Python's ``json`` with sorted keys, no
    spaces and ASCII only (numbers as Python writes them: parsing and writing again gives the
    same text, so the file's own layout does not matter).

    Raises:
        ValueError: the document cannot be written as JSON.
        RecursionError: it is nested too deeply.
    """
    body = {key: value for key, value in doc.items() if key != CHECKSUM_KEY}
    text = json.dumps(body, sort_keys=True, separators=(",", ":"), ensure_ascii=True)
    return hashlib.sha256(text.encode("ascii")).hexdigest()


def check_normalisation(spec: ModelSpec) -> None:
    """Refuse a normalisation no trained model has (see :data:`MAX_INPUT_SCALE` and the notes
    beside it): non-finite values, scales not positive or below :data:`MIN_SCALE`, means or
    scales beyond :data:`MAX_INPUT_SCALE` (features) or :data:`MAX_OUTPUT_SCALE` (outputs).

    Raises:
        ValueError: one line naming the first value out of its range.
    """
    if not get_kind(spec.kind).has_network:
        return
    for key, limit, unit in (("in_mean", MAX_INPUT_SCALE, "m or m/s"),
                             ("in_std", MAX_INPUT_SCALE, "m or m/s"),
                             ("out_mean", MAX_OUTPUT_SCALE, "m/s^2 or N m"),
                             ("out_std", MAX_OUTPUT_SCALE, "m/s^2 or N m")):
        values = np.asarray(getattr(spec, key), dtype=float)
        for i, value in enumerate(values.tolist()):
            where = f"normalisation.{key}[{i}] = {value:.6g}"
            if not np.isfinite(value):
                raise ValueError(f"{where}: not finite")
            if key.endswith("std") and value < MIN_SCALE:
                raise ValueError(f"{where}: a scale must be at least {MIN_SCALE:g} "
                                 "(below any sensor's resolution)")
            if abs(value) > limit:
                raise ValueError(f"{where}: beyond the plausible {limit:g} ({unit}; no "
                                 "docking flight has it)")


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
        vehicles: ``{"leader": {...}, "follower": {...}}`` with
            :data:`~aerodock.learning.training_vehicles.VEHICLE_KEYS`; default:
            ``training["data"]["vehicles"]`` (what the training data's flights said).

    Raises:
        ValueError: weights that do not match ``spec``, an implausible normalisation
            (:func:`check_normalisation`), or a ``path`` that is not a model directory.
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
    check_normalisation(spec)
    record = get_kind(spec.kind)
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
                     "of mass, N m, world NED" if record.torque else ""),
        **({"torque_units": TORQUE_UNITS} if record.torque else {}),
        "vehicles": normalise_vehicles(vehicles),
        "features": {
            "names": list(record.feature_names),
            "eps_pos_m": spec.eps_pos_m,
            "eps_vel_mps": spec.eps_vel_mps,
        },
        "outputs": list(record.output_names),
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
    doc[CHECKSUM_KEY] = model_checksum(doc)
    files[MODEL_JSON] = (json.dumps(doc, indent=2) + "\n").encode()
    write_dir_atomic(path, files)
    return path


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
            a ``model.json`` that does not match its checksum (version 2), unknown kind or
            activation, feature version mismatch, shapes that do not match, non-finite or
            implausible values, or a weights file that does not belong to ``model.json``.
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
        doc = json.loads(read_input_text(jpath, MODEL_JSON, MAX_JSON_BYTES))
    except InputError as err:
        raise ModelFileError(str(err)) from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as err:
        raise ModelFileError(f"{jpath}: corrupt model.json ({err})") from None
    except RecursionError:
        raise ModelFileError(f"{jpath}: corrupt model.json (nested too deeply)") from None
    if not isinstance(doc, dict) or doc.get("format") != MODEL_FORMAT:
        raise ModelFileError(f"{jpath}: not an aerodock model file")
    version = doc.get("version")
    if type(version) is not int or version < 1:
        raise ModelFileError(f"{jpath}: bad version {version!r}")
    if version > MODEL_VERSION:
        raise ModelFileError(
            f"{jpath}: model format version {version} is newer than this aerodock "
            f"({MODEL_VERSION}); upgrade aerodock"
        )
    _check_document(doc, version, jpath)
    kind = doc.get("kind")
    if not isinstance(kind, str) or kind not in REGISTRY:
        raise ModelFileError(f"{jpath}: unknown model kind {kind!r}")
    record = REGISTRY[kind]
    if doc.get("feature_version") != FEATURE_VERSION:
        raise ModelFileError(
            f"{jpath}: feature version {doc.get('feature_version')!r} does not match this "
            f"aerodock ({FEATURE_VERSION})"
        )
    if doc.get("units") != UNITS:
        raise ModelFileError(f"{jpath}: units {doc.get('units')!r}, expected {UNITS!r}")
    if record.torque and doc.get("torque_units") != TORQUE_UNITS:
        raise ModelFileError(f"{jpath}: torque_units {doc.get('torque_units')!r}, expected "
                             f"{TORQUE_UNITS!r}")
    if not record.has_network:
        if doc.get("layer_sizes") or doc.get("weights") is not None:
            raise ModelFileError(f"{jpath}: kind 'zero' with layer sizes or weights "
                                 "(edited kind?)")
        return ModelSpec(kind=kind), [], doc
    sizes = doc.get("layer_sizes")
    if (not isinstance(sizes, list) or len(sizes) < 2
            or not all(isinstance(s, int) and s > 0 for s in sizes)):
        raise ModelFileError(f"{jpath}: layer_sizes must be a list of positive integers")
    if sizes[0] != record.n_features or sizes[-1] != record.n_outputs:
        raise ModelFileError(
            f"{jpath}: layer_sizes {sizes} do not fit kind {kind!r} "
            f"({record.n_features} features, {record.n_outputs} outputs)"
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
    try:
        check_normalisation(spec)
        spec.weight_shapes()
    except ValueError as err:
        raise ModelFileError(f"{jpath}: {err}") from None
    return spec, _load_weights(path, spec, doc), doc


def _check_document(doc: dict[str, Any], version: int, jpath: Path) -> None:
    """Verify ``model.json``'s own checksum (version 2); refuse a version 1 file that has one."""
    claimed = doc.get(CHECKSUM_KEY)
    if version < 2:
        if CHECKSUM_KEY in doc:
            raise ModelFileError(f"{jpath}: format version {version} with {CHECKSUM_KEY} "
                                 "(version 2 files have it; edited version?)")
        return
    if not isinstance(claimed, str) or len(claimed) != 64:
        raise ModelFileError(f"{jpath}: {CHECKSUM_KEY} missing or malformed: the model file "
                             "cannot be verified (re-save the model with this aerodock)")
    try:
        actual = model_checksum(doc)
    except RecursionError:
        raise ModelFileError(f"{jpath}: corrupt model.json (nested too deeply)") from None
    except (ValueError, TypeError) as err:
        raise ModelFileError(f"{jpath}: corrupt model.json ({err})") from None
    if actual != claimed.lower():
        raise ModelFileError(f"{jpath}: does not match its {CHECKSUM_KEY} (edited or corrupt "
                             "after it was written); restore it or re-train the model")


def upgrade_model_dir(path: str | Path) -> Path:
    """Re-save a model directory in the current format (a version 1 one gets the document's
    checksum); its predictions do not change. Returns its path.

    Raises:
        ModelFileError: the directory does not load (see :func:`load_model_dir`).
        OSError: it cannot be written (the old files are left as they were).
    """
    spec, weights, doc = load_model_dir(path)
    path = Path(path)
    if path.name == MODEL_JSON:
        path = path.parent
    training = doc.get("training")
    return save_model_dir(path, spec, weights,
                          training=training if isinstance(training, dict) else None,
                          vehicles=doc.get("vehicles"))


def _load_weights(
    path: Path, spec: ModelSpec, doc: dict[str, Any]
) -> list[tuple[np.ndarray, np.ndarray]]:
    wpath = path / WEIGHTS_NPZ
    winfo = doc.get("weights")
    if not isinstance(winfo, dict):
        raise ModelFileError(f"{path / MODEL_JSON}: weights entry missing")
    try:
        blob = read_input_bytes(wpath, WEIGHTS_NPZ, MAX_NPZ_BYTES)
    except FileNotFoundError:
        raise ModelFileError(f"{wpath}: not found") from None
    except InputError as err:
        raise ModelFileError(str(err)) from None
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
