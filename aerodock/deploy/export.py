"""ONNX export of a trained downwash model, built from ``weights.npz`` with ``onnx`` alone.

The graph (opset 17) is written operator by operator from the model directory: the SO(2)
feature map of :mod:`aerodock.learning.features`, the MLP with the input standardisation and the
output scaling folded into its first and last layers (as in the NumPy runtime), and the rotation
of the invariant outputs back to the world. No PyTorch is imported: ``aerodock[export]`` is
enough.

Inputs ``x`` (n, 9: ``[dp, v_A, v_B]``, NED) and ``leader_R`` (n, 3, 3, leader body to world),
and for a leader-aware model ``wake_scales`` (``so2-leader``: n, 3: the leader's hover induced
velocity, m/s, its size ``sqrt(n) R``, m, the follower's hover induced velocity, m/s;
``so2-pair``: n, 4, and the follower's size ``sqrt(n) R``, m; see
:func:`aerodock.learning.features.wake_scales`);
output ``f_ext_mps2`` (n, 3, NED), with a dynamic batch axis ``n``; a ``so2-wrench`` model has a
second output, ``tau_ext_nm`` (n, 3: the wake's torque on the follower, N m, world NED; rotate it
with the follower's attitude for the body frame), from its last three network outputs through the
same frame. ONNX fixes the element type
of a graph's inputs, so the export takes ``dtype``: ``"float32"`` (the default, what most
runtimes want) or ``"float64"`` (the whole graph in double precision, equal to the NumPy runtime
to rounding). :func:`check_onnx` feeds whichever type the file declares.

``metadata_props`` carries what ``model.json`` says about the model (keys ``aerodock.*``): the
format, kind, units, input and output, the vehicles it was trained on (JSON), the label bases of
its training flights (JSON: a list such as ``["thrust"]``, or ``null`` where not recorded; see
docs/learning.md, *Label basis*), the feature version and regularisation, the weights' SHA-256,
``model.json``'s own checksum, the aerodock version, and the element type.

:func:`export_onnx` checks the file it writes before it takes the output's name: onnxruntime runs
it on random scenes beside the NumPy predictor (:func:`onnx_differences`), and a difference beyond
:data:`TOLERANCE` (relative to the predictions' size where they exceed one) raises
:class:`ExportCheckError` with nothing written. A kill during the check leaves the old file (or
none) and a temporary file that the next write to the same path removes. Without onnxruntime the
file is written unchecked, and the result says so.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

import numpy as np

from aerodock.fileio import atomic_open
from aerodock.learning.kinds import get_kind
from aerodock.learning.kinds.trace import AXIS_INPUTS, BODY_INPUTS, trace_prediction
from aerodock.learning.modelfile import (
    CHECKSUM_KEY,
    MODEL_FORMAT,
    TORQUE_UNITS,
    UNITS,
    ModelSpec,
    load_model_dir,
)
from aerodock.learning.training_vehicles import normalise_vehicles

ONNX_OPSET = 17
INPUT_NAMES = ("x", "leader_R")
SCALES_INPUT_NAME = "wake_scales"
"""The leader-aware kinds' third input (n, 3): leader_vh_mps, leader_size_m, follower_vh_mps."""
OUTPUT_NAME = "f_ext_mps2"
TORQUE_OUTPUT_NAME = "tau_ext_nm"
DTYPES = ("float32", "float64")
# Largest difference the export accepts between onnxruntime and the NumPy predictor, per element
# type, in the outputs' units (m/s^2, N m), scaled by the largest prediction where that exceeds
# one (float32 arithmetic is relative: about 1e-7 of the values through a 64-wide layer).
TOLERANCE = {"float32": 1e-5, "float64": 1e-10}


class ExportCheckError(ValueError):
    """The ONNX graph does not reproduce the NumPy predictor (or cannot be run); nothing is
    written. One-line message."""


def _source(model: Any) -> tuple[ModelSpec, list[tuple[np.ndarray, np.ndarray]], dict[str, Any]]:
    """Spec, weights and ``model.json``-like document of a model directory or trained model."""
    if isinstance(model, str | Path):
        return load_model_dir(model)
    module = getattr(model, "model", model)  # a TrainedModel holds the module in .model
    if hasattr(module, "spec") and hasattr(module, "weights"):
        if hasattr(module, "eval"):
            module.eval()
        info = getattr(model, "info", {}) or {}
        data = info.get("data") if isinstance(info, dict) else None
        vehicles = data.get("vehicles") if isinstance(data, dict) else None
        return module.spec(), module.weights(), {"kind": module.spec().kind, "units": UNITS,
                                                 "vehicles": vehicles, "training": info}
    raise TypeError(f"cannot export {type(model).__name__}: give a model directory or a "
                    "trained model")


class _Graph:
    """A small builder of ONNX nodes with generated names (one element type throughout)."""

    def __init__(self, dtype: str) -> None:
        from onnx import TensorProto, helper, numpy_helper

        self.helper, self.numpy_helper = helper, numpy_helper
        self.np_dtype = np.dtype(dtype)
        self.elem = TensorProto.FLOAT if dtype == "float32" else TensorProto.DOUBLE
        self.nodes: list[Any] = []
        self.inits: list[Any] = []
        self.count = 0

    def _name(self, hint: str) -> str:
        self.count += 1
        return f"{hint}_{self.count}"

    def const(self, value: Any, hint: str = "c", dtype: Any = None) -> str:
        name = self._name(hint)
        arr = np.asarray(value, dtype=dtype or self.np_dtype)
        self.inits.append(self.numpy_helper.from_array(arr, name))
        return name

    def op(self, op_type: str, *inputs: str, hint: str | None = None, **attrs: Any) -> str:
        out = self._name(hint or op_type.lower())
        self.nodes.append(self.helper.make_node(op_type, list(inputs), [out], **attrs))
        return out

    def col(self, mat: str, row: int, col: int) -> str:
        """``mat[:, row, col]`` as an (n,) tensor of a (n, 3, 3) tensor."""
        i64 = np.int64
        piece = self.op("Slice", mat, self.const([row, col], "s", i64),
                        self.const([row + 1, col + 1], "e", i64), self.const([1, 2], "ax", i64))
        return self.op("Reshape", piece, self.const([-1], "shape", i64))

    def add(self, a: str, b: str) -> str:
        return self.op("Add", a, b)

    def sub(self, a: str, b: str) -> str:
        return self.op("Sub", a, b)

    def mul(self, a: str, b: str) -> str:
        return self.op("Mul", a, b)

    def div(self, a: str, b: str) -> str:
        return self.op("Div", a, b)

    def sqrt(self, a: str) -> str:
        return self.op("Sqrt", a)

    def stack(self, parts: list[str]) -> str:
        """(n,) tensors side by side: (n, k)."""
        axis = self.const([1], "axis", np.int64)
        return self.op("Concat", *[self.op("Unsqueeze", p, axis) for p in parts], axis=1)


_ONNX_OPS = {"add": "Add", "sub": "Sub", "mul": "Mul", "div": "Div", "neg": "Neg", "sqrt": "Sqrt"}


def _predicted(g: _Graph, spec: ModelSpec, weights: list[tuple[np.ndarray, np.ndarray]]
               ) -> tuple[str, str | None]:
    """The force (n, 3) and a torque kind's torque (n, 3) (else None): the kind's traced
    prediction (:func:`aerodock.learning.kinds.trace.trace_prediction`) written node by node,
    the network in the middle."""
    kind = get_kind(spec.kind)
    if kind.world_frame:
        return _mlp(g, "x", spec, weights), None
    pred = trace_prediction(kind, spec.eps_pos_m**2, spec.eps_vel_mps**2)
    body = g.op("MatMul", g.op("Reshape", "x", g.const([-1, 3, 3], "shape", np.int64)),
                "leader_R", hint="body")  # rows: R^T dp, R^T v_A, R^T v_B
    scales = (g.op("Unsqueeze", SCALES_INPUT_NAME, g.const([1], "axis", np.int64))
              if kind.n_wake_scales else "")
    names: list[str] = []
    c3 = ""
    for node in pred.trace.nodes:
        if node.op == "const":
            names.append(g.const(node.value, "k"))
        elif node.op != "input":
            names.append(g.op(_ONNX_OPS[node.op], *[names[i] for i in node.args]))
        elif node.name in BODY_INPUTS:
            row, col = divmod(BODY_INPUTS.index(node.name), 3)
            names.append(g.col(body, row, col))
        elif node.name in AXIS_INPUTS:
            names.append(g.col("leader_R", int(node.name[1]), int(node.name[2])))
        elif node.name.startswith("s"):
            names.append(g.col(scales, 0, int(node.name[1:])))
        else:  # c{k}: the network's outputs (every feature is computed before them)
            if not c3:
                c = _mlp(g, g.stack([names[s.index] for s in pred.z]), spec, weights)
                c3 = g.op("Unsqueeze", c, g.const([1], "axis", np.int64))
            names.append(g.col(c3, 0, int(node.name[1:])))
    force = g.stack([names[s.index] for s in pred.force])
    if pred.torque is None:
        return force, None
    return force, g.stack([names[s.index] for s in pred.torque])


def _mlp(g: _Graph, z: str, spec: ModelSpec, weights: list[tuple[np.ndarray, np.ndarray]]
         ) -> str:
    from aerodock.learning.runtime import folded_layers

    layers = folded_layers(spec, weights)
    record = get_kind(spec.kind)
    e, n_features = record.ego_features, record.n_features
    h, ego = z, ""
    if e:  # deep sets: phi reads the neighbour's features, rho phi's output and the ego ones
        i64 = np.int64
        h, ego = (g.op("Slice", z, g.const([a], "s", i64), g.const([b], "e", i64),
                       g.const([1], "ax", i64)) for a, b in ((0, n_features - e),
                                                             (n_features - e, n_features)))
    for i, (w, b) in enumerate(layers):
        if e and i == record.phi_layers:
            h = g.op("Concat", h, ego, axis=1)
        h = g.op("Add", g.op("MatMul", h, g.const(w.T, "W")), g.const(b, "b"))
        if i < len(layers) - 1:
            h = g.op("Tanh", h) if spec.activation == "tanh" else g.mul(h, g.op("Sigmoid", h))
    return h


def build_onnx(spec: ModelSpec, weights: list[tuple[np.ndarray, np.ndarray]],
               doc: dict[str, Any] | None = None, *, dtype: str = "float32",
               opset: int = ONNX_OPSET) -> Any:
    """The ONNX ``ModelProto`` of a model (see the module docstring); checked by ``onnx``.

    Raises:
        ValueError: an unknown ``dtype``.
    """
    import onnx
    from onnx import helper

    if dtype not in DTYPES:
        raise ValueError(f"dtype {dtype!r}: use float32 or float64")
    g = _Graph(dtype)
    kind = get_kind(spec.kind)
    if not kind.has_network:
        n = g.op("Slice", g.op("Shape", "x"), g.const([0], "s", np.int64),
                 g.const([1], "e", np.int64))
        shape = g.op("Concat", n, g.const([3], "three", np.int64), axis=0)
        zero = helper.make_tensor("zero", g.elem, [1], [0.0])
        out = g.op("ConstantOfShape", shape, value=zero)
    else:
        out, torque = _predicted(g, spec, weights)
    outputs = [OUTPUT_NAME]
    g.nodes.append(helper.make_node("Identity", [out], [OUTPUT_NAME]))
    if kind.torque:  # the torque's components: the network's last K
        g.nodes.append(helper.make_node("Identity", [torque], [TORQUE_OUTPUT_NAME]))
        outputs.append(TORQUE_OUTPUT_NAME)
    inputs = [helper.make_tensor_value_info("x", g.elem, ["n", 9]),
              helper.make_tensor_value_info("leader_R", g.elem, ["n", 3, 3])]
    if kind.n_wake_scales:
        inputs.append(helper.make_tensor_value_info(SCALES_INPUT_NAME, g.elem,
                                                    ["n", kind.n_wake_scales]))
    graph = helper.make_graph(
        g.nodes, f"aerodock_{spec.kind.replace('-', '_')}", inputs,
        [helper.make_tensor_value_info(name, g.elem, ["n", 3]) for name in outputs],
        initializer=g.inits,
    )
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", opset)],
                              producer_name="aerodock")
    model.ir_version = min(model.ir_version, 9)  # readable by onnxruntime releases of 2024 on
    helper.set_model_props(model, _metadata(spec, weights, doc or {}, dtype))
    onnx.checker.check_model(model)
    return model


def label_bases(doc: dict[str, Any]) -> list[str] | None:
    """The label bases of a model's training flights (``model.json`` ->
    ``training.data.label_bases``), or None where the model does not record them."""
    training = doc.get("training")
    data = training.get("data") if isinstance(training, dict) else None
    bases = data.get("label_bases") if isinstance(data, dict) else None
    if isinstance(bases, list) and all(isinstance(b, str) for b in bases):
        return list(bases)
    return None


def _metadata(spec: ModelSpec, weights: list[tuple[np.ndarray, np.ndarray]],
              doc: dict[str, Any], dtype: str) -> dict[str, str]:
    sha = (doc.get("weights") or {}).get("sha256") if isinstance(doc.get("weights"), dict) \
        else None
    if sha is None and weights:
        sha = hashlib.sha256(b"".join(np.asarray(a, np.float32).tobytes()
                                      for pair in weights for a in pair)).hexdigest()
    return {
        "aerodock.format": MODEL_FORMAT,
        "aerodock.kind": spec.kind,
        "aerodock.units": UNITS,
        "aerodock.input": "x (n, 9) = [dp = p_follower - p_leader, v_leader, v_follower] "
                          "(m, m/s, NED); leader_R (n, 3, 3) leader attitude, body to world",
        "aerodock.output": "f_ext_mps2 (n, 3): predicted downwash acceleration on the "
                           "follower, m/s^2, NED" + (
                               f"; {TORQUE_OUTPUT_NAME} (n, 3): predicted wake torque on the "
                               f"follower about its centre of mass, {TORQUE_UNITS}"
                               if get_kind(spec.kind).torque else ""),
        **({"aerodock.torque_units": TORQUE_UNITS} if get_kind(spec.kind).torque else {}),
        "aerodock.vehicles": json.dumps(normalise_vehicles(doc.get("vehicles"))),
        "aerodock.label_bases": json.dumps(label_bases(doc)),
        "aerodock.feature_version": str(spec.feature_version),
        "aerodock.eps_pos_m": repr(spec.eps_pos_m),
        "aerodock.eps_vel_mps": repr(spec.eps_vel_mps),
        "aerodock.weights_sha256": sha or "",
        "aerodock.model_sha256": str(doc.get(CHECKSUM_KEY) or ""),
        "aerodock.aerodock_version": str(doc.get("aerodock_version", "")),
        "aerodock.dtype": dtype,
    }


def export_onnx(model: Any, out: str | Path, *, dtype: str = "float32",
                opset: int = ONNX_OPSET) -> Path:
    """Export ``model`` to an ONNX file, checked and atomically (see :func:`export_checked`).

    Raises:
        ModelFileError: ``model`` is a directory with missing, corrupt or mismatched files.
        ExportCheckError: the graph does not reproduce the NumPy predictor within
            :data:`TOLERANCE`; nothing is written.
        ValueError: an unknown ``dtype``.
    """
    return export_checked(model, out, dtype=dtype, opset=opset)[0]


def export_checked(model: Any, out: str | Path, *, dtype: str = "float32",
                   opset: int = ONNX_OPSET, n_check: int = 256
                   ) -> tuple[Path, dict[str, float] | None]:
    """Export ``model`` to an ONNX file and check it before it takes the name ``out``.

    The graph is written to a temporary file beside ``out``; onnxruntime runs that file beside
    the NumPy predictor (:func:`onnx_differences`, ``n_check`` random scenes) and only a file
    within :data:`TOLERANCE` is renamed to ``out``, so ``out`` never holds an unchecked file
    (the old one stays until then, and stays if the check fails or the process is killed).

    Args:
        model: a model directory, or a trained model (``TrainedModel`` or module of this
            package: its ``spec()`` and effective ``weights()`` are used).
        out: the ``.onnx`` file to write.
        dtype: element type of the graph's inputs, output and arithmetic.
        opset: ONNX opset version.
        n_check: scenes of the check.

    Returns:
        ``(out, differences)``: the differences per output as :func:`onnx_differences` gives
        them, or None where onnxruntime is not installed (the file is then written unchecked).

    Raises:
        ModelFileError: ``model`` is a directory with missing, corrupt or mismatched files.
        ExportCheckError: a difference beyond the tolerance, or a file onnxruntime cannot run.
        ValueError: an unknown ``dtype``.
    """
    spec, weights, doc = _source(model)
    proto = build_onnx(spec, weights, doc, dtype=dtype, opset=opset)
    predictor = _predictor(spec, weights, doc)
    found: dict[str, dict[str, float] | None] = {"diffs": None}

    def verify(tmp: Path) -> None:
        found["diffs"] = _check_file(tmp, predictor, dtype, n_check)

    out = Path(out)
    with atomic_open(out, "wb", verify=verify) as fh:
        fh.write(proto.SerializeToString())
    return out, found["diffs"]


def _predictor(spec: ModelSpec, weights: list[tuple[np.ndarray, np.ndarray]],
               doc: dict[str, Any]) -> Any:
    """The NumPy predictor the export is checked against."""
    from aerodock.learning.runtime import Predictor, ZeroPredictor

    if not get_kind(spec.kind).has_network:
        return ZeroPredictor(doc)
    return Predictor(spec, weights, doc)


def _check_file(path: Path, predictor: Any, dtype: str, n: int) -> dict[str, float] | None:
    """Differences per output of the ONNX file at ``path``; None without onnxruntime.

    Raises:
        ExportCheckError: beyond :data:`TOLERANCE`, or onnxruntime cannot run the file.
    """
    try:
        import onnxruntime  # noqa: F401
    except ImportError:
        return None
    try:
        compared = _compare(path, predictor, n=n, rng=None)
    except Exception as err:  # onnxruntime's own errors are plain Exceptions
        raise ExportCheckError(f"onnxruntime cannot run the exported graph "
                               f"({type(err).__name__}: {' '.join(str(err).split())[:200]}); "
                               "nothing written") from None
    units = {OUTPUT_NAME: "m/s^2", TORQUE_OUTPUT_NAME: "N m"}
    for name, (diff, scale) in compared.items():
        limit = TOLERANCE[dtype] * max(1.0, scale)
        if not diff <= limit:  # a NaN fails too
            raise ExportCheckError(
                f"the exported {name} differs from the NumPy model by {diff:.3g} {units[name]} "
                f"(tolerance {limit:.3g} for {dtype}); nothing written"
            )
    return {name: diff for name, (diff, _) in compared.items()}


def read_onnx_metadata(path: str | Path) -> dict[str, str]:
    """The ``metadata_props`` of an ONNX file, as a dict."""
    import onnx

    return {p.key: p.value for p in onnx.load(str(path), load_external_data=False)
            .metadata_props}


def check_onnx(
    path: str | Path,
    predictor: Any,
    *,
    n: int = 256,
    rng: np.random.Generator | None = None,
) -> float:
    """Max absolute difference between an ONNX file (onnxruntime) and ``predictor`` over every
    output: the force (m/s²) and, for a wrench model, the torque (N m); see
    :func:`onnx_differences` for each.

    Raises:
        ImportError: onnxruntime is not installed.
    """
    return max(onnx_differences(path, predictor, n=n, rng=rng).values())


def onnx_differences(
    path: str | Path,
    predictor: Any,
    *,
    n: int = 256,
    rng: np.random.Generator | None = None,
) -> dict[str, float]:
    """Max absolute difference per output between an ONNX file and ``predictor``:
    ``{"f_ext_mps2": m/s²}`` and, for a wrench model, ``"tau_ext_nm"`` (N m).

    Inputs are random scenes around and below the leader (tilted and yawed), given in the
    element type the file declares; the predictor sees the same (rounded) numbers.

    Raises:
        ImportError: onnxruntime is not installed.
        ValueError: the file's outputs do not match the predictor's (a torque one or not).
    """
    return {name: diff for name, (diff, _) in _compare(path, predictor, n=n, rng=rng).items()}


def _compare(path: str | Path, predictor: Any, *, n: int,
             rng: np.random.Generator | None) -> dict[str, tuple[float, float]]:
    """Per output: (max absolute difference, max absolute prediction of ``predictor``)."""
    import onnxruntime as ort

    from aerodock.geometry import euler_to_rotmat

    rng = np.random.default_rng(0) if rng is None else rng
    x = np.concatenate([
        rng.uniform([-0.6, -0.6, -0.3], [0.6, 0.6, 1.8], size=(n, 3)),
        rng.normal(0.0, 0.3, size=(n, 6)),
    ], axis=1)
    rot = euler_to_rotmat(rng.normal(0, 0.1, n), rng.normal(0, 0.1, n), rng.uniform(-3, 3, n))
    # The model's bytes, not its name: onnxruntime takes only a UTF-8 path, and a file name
    # need not be one (a POSIX name is any bytes).
    sess = ort.InferenceSession(Path(path).read_bytes(), providers=["CPUExecutionProvider"])
    dtype = np.float64 if sess.get_inputs()[0].type == "tensor(double)" else np.float32
    xs, rs = x.astype(dtype), rot.astype(dtype)
    feeds = {"x": xs, "leader_R": rs}
    scales = None
    if getattr(predictor, "needs_wake_scales", False):  # leaders of 0.25-4x a hover's v_h^2
        scales = np.stack([rng.uniform(2.0, 9.0, n), rng.uniform(0.03, 0.3, n),
                           rng.uniform(3.0, 8.0, n), rng.uniform(0.03, 0.3, n)],
                          axis=1)[:, :get_kind(predictor.kind).n_wake_scales]
        feeds[SCALES_INPUT_NAME] = scales.astype(dtype)
        scales = feeds[SCALES_INPUT_NAME].astype(float)
    if (SCALES_INPUT_NAME in [i.name for i in sess.get_inputs()]) != (scales is not None):
        raise ValueError(f"{path}: inputs do not match a {predictor.kind!r} model")
    names = [o.name for o in sess.get_outputs()]
    has_torque = bool(getattr(predictor, "has_torque", False))
    if (TORQUE_OUTPUT_NAME in names) != has_torque:
        raise ValueError(f"{path}: outputs {names} do not match a {predictor.kind!r} model")
    got = dict(zip(names, sess.run(None, feeds), strict=True))
    if has_torque:
        force, torque = predictor.predict_wrench(xs.astype(float), rs.astype(float))
    elif scales is not None:
        force, torque = predictor.predict(xs.astype(float), rs.astype(float), scales), None
    else:
        force, torque = predictor.predict(xs.astype(float), rs.astype(float)), None
    out = {OUTPUT_NAME: _diff_and_scale(got[OUTPUT_NAME], force)}
    if torque is not None:
        out[TORQUE_OUTPUT_NAME] = _diff_and_scale(got[TORQUE_OUTPUT_NAME], torque)
    return out


def _diff_and_scale(got: np.ndarray, want: np.ndarray) -> tuple[float, float]:
    with np.errstate(invalid="ignore", over="ignore"):
        diff = np.abs(np.asarray(got, dtype=float) - want)
    return (float(np.max(diff)) if diff.size else 0.0,
            float(np.max(np.abs(want))) if want.size else 0.0)
