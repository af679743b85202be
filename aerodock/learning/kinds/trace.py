"""Symbolic tracing of a kind's feature map: one run records its arithmetic as a graph.

Tracing calls the kind's feature map once on :class:`Sym` values; every ``+ - * /``, negation
and ``sqrt`` on them adds a :class:`Node`, in the order the feature map computes them. Two
back-ends read the recorded graph:

* :func:`compile_scalar` turns it into one straight-line Python function of floats (the NumPy
  runtime's one-sample hot path: as fast as arithmetic written out by hand, and the same
  operations in the same order as the batched path, so the same numbers);
* the ONNX export (:mod:`aerodock.deploy.export`) writes one graph node per recorded node.

The generated source depends only on the kind's code (this package): numbers from a model file
(the regularisation constants) are bound as values, never written into the source.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from aerodock.learning.kinds.base import Kind, Scene

_BINARY = {"add": "+", "sub": "-", "mul": "*", "div": "/"}


@dataclass
class Node:
    """One recorded operation: ``op`` (``input``, ``const``, ``add``, ``sub``, ``mul``, ``div``,
    ``neg``, ``sqrt``) of ``args`` (earlier nodes' indices), or an input's name or a constant."""

    op: str
    args: tuple[int, ...] = ()
    name: str = ""
    value: float = 0.0


@dataclass
class Trace:
    """The graph of one traced computation (nodes in computation order)."""

    nodes: list[Node] = field(default_factory=list)

    def add(self, node: Node) -> Sym:
        self.nodes.append(node)
        return Sym(self, len(self.nodes) - 1)

    def input(self, name: str) -> Sym:
        """A named input."""
        return self.add(Node("input", name=name))

    def const(self, value: Any) -> Sym:
        """A constant (or the value itself if already traced)."""
        if isinstance(value, Sym):
            return value
        return self.add(Node("const", value=float(value)))

    def sqrt(self, a: Sym) -> Sym:
        """The square root."""
        return self.add(Node("sqrt", (self.const(a).index,)))


class Sym:
    """A traced per-sample scalar (an index into its :class:`Trace`)."""

    __slots__ = ("index", "trace")

    def __init__(self, trace: Trace, index: int) -> None:
        self.trace, self.index = trace, index

    def _bin(self, op: str, a: Any, b: Any) -> Sym:
        t = self.trace
        return t.add(Node(op, (t.const(a).index, t.const(b).index)))

    def __add__(self, o: Any) -> Sym:
        return self._bin("add", self, o)

    def __radd__(self, o: Any) -> Sym:
        return self._bin("add", o, self)

    def __sub__(self, o: Any) -> Sym:
        return self._bin("sub", self, o)

    def __rsub__(self, o: Any) -> Sym:
        return self._bin("sub", o, self)

    def __mul__(self, o: Any) -> Sym:
        return self._bin("mul", self, o)

    def __rmul__(self, o: Any) -> Sym:
        return self._bin("mul", o, self)

    def __truediv__(self, o: Any) -> Sym:
        return self._bin("div", self, o)

    def __rtruediv__(self, o: Any) -> Sym:
        return self._bin("div", o, self)

    def __neg__(self) -> Sym:
        return self.trace.add(Node("neg", (self.index,)))


BODY_INPUTS = ("px", "py", "pz", "ax", "ay", "az", "bx", "by", "bz")
AXIS_INPUTS = tuple(f"r{i}{k}" for k in range(3) for i in range(3))  # a1, a2, a3 in turn


def trace_kind(kind: Kind, eps_p2: Any, eps_v2: Any
               ) -> tuple[Trace, list[Sym], list[tuple[Sym, ...]]]:
    """Trace ``kind``'s feature map on the inputs :data:`BODY_INPUTS` (the leader-body
    components), :data:`AXIS_INPUTS` (``r{row}{col}`` of ``R_A``) and ``s0, s1, ...`` (the wake
    scales); ``eps_p2`` and ``eps_v2`` as given (numbers, or traced values).

    Returns:
        ``(trace, z, frame)``: the graph, the F features and the K frame vectors.
    """
    if kind.features is None:
        raise ValueError(f"kind {kind.name!r} has no feature map")
    t = Trace()
    body = [t.input(n) for n in BODY_INPUTS]
    axes = [tuple(t.input(n) for n in AXIS_INPUTS[3 * k:3 * k + 3]) for k in range(3)]
    scales = [t.input(f"s{k}") for k in range(kind.n_wake_scales)]
    z, frame = kind.features(Scene(body, axes, scales, eps_p2, eps_v2), t)
    return t, [t.const(v) for v in z], [tuple(t.const(c) for c in v) for v in frame]


@dataclass
class Prediction:
    """A traced prediction: features, the network's outputs (inputs ``c0, c1, ...``) and what
    the frame makes of them."""

    trace: Trace
    z: list[Sym]
    outputs: list[Sym]
    force: list[Sym]
    torque: list[Sym] | None


def _combine(outputs: Sequence[Sym], frame: Sequence[tuple[Sym, ...]]) -> list[Sym]:
    """``sum_k c_k frame_k``, component by component, left to right."""
    result = []
    for i in range(3):
        f = outputs[0] * frame[0][i]
        for ck, v in zip(outputs[1:], frame[1:]):
            f = f + ck * v[i]
        result.append(f)
    return result


def trace_prediction(kind: Kind, eps_p2: Any, eps_v2: Any) -> Prediction:
    """Trace a kind's whole prediction: :func:`trace_kind`, then the network's outputs as inputs
    ``c0 ... c{n_outputs-1}`` and the force ``sum_k c_k frame_k`` (a torque kind's torque from
    its last K outputs, through the same frame)."""
    t, z, frame = trace_kind(kind, eps_p2, eps_v2)
    outs = [t.input(f"c{k}") for k in range(kind.n_outputs)]
    k = len(frame)
    return Prediction(t, z, outs, _combine(outs[:k], frame),
                      _combine(outs[k:], frame) if kind.torque else None)


def compile_scalar(kind: Kind, eps_p2: float, eps_v2: float
                   ) -> Callable[[Sequence[float], Sequence[Sequence[float]],
                                  Callable[[list[float]], list[float]]], list[float]]:
    """The one-sample prediction of a kind with a feature map (and no wake scales), as one
    Python function.

    The function takes ``x`` (9 floats), ``R`` (3 rows of 3 floats) and ``network`` (features
    to outputs, a list of floats) and returns the world force ``[f_n, f_e, f_d]``: the body
    components ``R^T w``, the kind's features, ``network(z)`` and ``sum_k c_k frame_k``, written
    out in the order the batched path computes them.
    """
    if kind.n_wake_scales:
        raise ValueError(f"kind {kind.name!r} takes wake scales: no one-sample function")
    pred = trace_prediction(kind, eps_p2, eps_v2)
    t, z, outs, force = pred.trace, pred.z, pred.outputs, pred.force
    lines = ["def predict(x, R, network):",
             "    dx, dy, dz, ax, ay, az, bx, by, bz = x",
             "    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = R"]
    body = {"px": "r00 * dx + r10 * dy + r20 * dz", "py": "r01 * dx + r11 * dy + r21 * dz",
            "pz": "r02 * dx + r12 * dy + r22 * dz", "ax": "r00 * ax + r10 * ay + r20 * az",
            "ay": "r01 * ax + r11 * ay + r21 * az", "az": "r02 * ax + r12 * ay + r22 * az",
            "bx": "r00 * bx + r10 * by + r20 * bz", "by": "r01 * bx + r11 * by + r21 * bz",
            "bz": "r02 * bx + r12 * by + r22 * bz"}
    consts: dict[str, float] = {}
    needed = _needed(t, [*z, *force])
    ref = {i: f"v{i}" for i in range(len(t.nodes))}  # how the source names each node
    for i, node in enumerate(t.nodes):
        if i not in needed:
            continue
        if node.op == "input" and node.name in body:
            lines.append(f"    v{i} = {body[node.name]}")
        elif node.op == "input" and i == outs[0].index:  # all features computed: the network
            names = ", ".join(ref[s.index] for s in outs)
            feats = ", ".join(ref[s.index] for s in z)
            lines.append(f"    {names}, *_ = network([{feats}])")
        elif node.op == "input" and node.name.startswith("r"):
            ref[i] = node.name  # the rotation's entries: by their names
        elif node.op == "const":
            ref[i] = f"k{i}"  # the constants (the regularisation's among them): bound below
            consts[ref[i]] = node.value
        elif node.op in _BINARY:
            a, b = node.args
            lines.append(f"    v{i} = {ref[a]} {_BINARY[node.op]} {ref[b]}")
        elif node.op == "neg":
            lines.append(f"    v{i} = -{ref[node.args[0]]}")
        elif node.op == "sqrt":
            lines.append(f"    v{i} = sqrt({ref[node.args[0]]})")
    lines.append(f"    return [{', '.join(ref[s.index] for s in force)}]")
    namespace: dict[str, Any] = {"sqrt": math.sqrt, **consts}
    exec(compile("\n".join(lines), f"<aerodock kind {kind.name}>", "exec"), namespace)  # noqa: S102
    return namespace["predict"]


def _needed(t: Trace, roots: Sequence[Sym]) -> set[int]:
    """Indices of the nodes the ``roots`` depend on."""
    seen: set[int] = set()
    stack = [s.index for s in roots]
    while stack:
        i = stack.pop()
        if i not in seen:
            seen.add(i)
            stack.extend(t.nodes[i].args)
    return seen
