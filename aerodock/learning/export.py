"""ONNX export of a trained downwash model (features + MLP + rotation back, in one graph).

The exported graph has inputs ``x`` (n, 9, float32: ``[dp, v_A, v_B]``, NED) and ``leader_R``
(n, 3, 3, float32, leader body to world) and output ``f_ext_mps2`` (n, 3, float32, NED), with a
dynamic batch axis. It uses the legacy TorchScript exporter (``dynamo=False``): the dynamo
exporter of torch 2.13 needs ``onnxscript``, which aerodock does not depend on; the graph only
uses elementary operators (MatMul/Gemm, Tanh, Pow, ReduceSum, Concat, Slice), opset 17.
"""

from __future__ import annotations

import os
import tempfile
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import nn

from aerodock.learning.models import load_torch_model, model_from_spec

ONNX_OPSET = 17
INPUT_NAMES = ("x", "leader_R")
OUTPUT_NAME = "f_ext_mps2"


class _KeepInputs(nn.Module):
    """Makes the graph use ``leader_R`` even when the model ignores it (``mlp``, ``zero``), so
    that every exported file has the same two inputs (the exporter drops unused inputs). Adds an
    exact zero for finite inputs."""

    def __init__(self, inner: nn.Module) -> None:
        super().__init__()
        self.inner = inner

    def forward(self, x: torch.Tensor, leader_R: torch.Tensor) -> torch.Tensor:
        return self.inner(x, leader_R) + 0.0 * leader_R[:, :, 0] * x[:, 0:1]


def _as_module(model: Any) -> nn.Module:
    """A plain float32 module: rebuilt from the effective weights, so spectral-norm
    parametrisations (not exportable) are folded in and the caller's module is left alone."""
    if hasattr(model, "model") and isinstance(model.model, nn.Module):  # TrainedModel
        model = model.model
    if isinstance(model, nn.Module):
        model.eval()
        return model_from_spec(model.spec(), model.weights())
    return load_torch_model(model)


def export_onnx(model: Any, out: str | Path, *, opset: int = ONNX_OPSET) -> Path:
    """Export ``model`` to an ONNX file, atomically.

    Args:
        model: a model directory, a ``TrainedModel`` or a torch module of this package.
        out: the ``.onnx`` file to write.
        opset: ONNX opset version.

    Raises:
        ModelFileError: ``model`` is a directory with missing, corrupt or mismatched files.
    """
    module = _as_module(model).float().eval()
    if getattr(module, "kind", "") in ("mlp", "zero"):
        module = _KeepInputs(module).eval()
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    x = torch.zeros(2, 9)
    x[:, 2] = 0.5
    rot = torch.eye(3).expand(2, 3, 3).contiguous()
    fd, tmp = tempfile.mkstemp(dir=out.parent, prefix=f".{out.name}.", suffix=".tmp")
    os.close(fd)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            torch.onnx.export(
                module, (x, rot), tmp,
                input_names=list(INPUT_NAMES), output_names=[OUTPUT_NAME],
                dynamic_axes={"x": {0: "n"}, "leader_R": {0: "n"}, OUTPUT_NAME: {0: "n"}},
                opset_version=opset, dynamo=False,
            )
        os.replace(tmp, out)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return out


def check_onnx(
    path: str | Path,
    predictor: Any,
    *,
    n: int = 256,
    rng: np.random.Generator | None = None,
) -> float:
    """Max absolute difference (m/s²) between an ONNX file (onnxruntime) and ``predictor``.

    Inputs are random scenes around and below the leader (tilted and yawed).

    Raises:
        ImportError: onnxruntime is not installed.
    """
    import onnxruntime as ort

    from aerodock.geometry import euler_to_rotmat

    rng = np.random.default_rng(0) if rng is None else rng
    x = np.concatenate([
        rng.uniform([-0.6, -0.6, -0.3], [0.6, 0.6, 1.8], size=(n, 3)),
        rng.normal(0.0, 0.3, size=(n, 6)),
    ], axis=1)
    rot = euler_to_rotmat(rng.normal(0, 0.1, n), rng.normal(0, 0.1, n), rng.uniform(-3, 3, n))
    sess = ort.InferenceSession(str(path), providers=["CPUExecutionProvider"])
    (got,) = sess.run(None, {"x": x.astype(np.float32), "leader_R": rot.astype(np.float32)})
    want = predictor.predict(x.astype(np.float32).astype(float),
                             rot.astype(np.float32).astype(float))
    return float(np.max(np.abs(got - want)))
