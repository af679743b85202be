"""Deploy a trained downwash model: load it, predict the wake on the follower, export ONNX.

``Predictor.load`` reads a model directory (``aerodock train``, ``collect`` or
``examples/train_on_logs.py`` write one) with NumPy alone: what a flight computer runs. Its
``predict(x, leader_R)`` takes ``x = [dp, v_leader, v_follower]`` (n, 9), NED, SI, with
``dp = p_follower - p_leader`` (a follower below the leader has ``dp_z > 0``), and the leader's
attitude (n, 3, 3); it returns the wake's acceleration on the follower (n, 3), m/s², NED (down
is positive). The follower's controller subtracts it (``--compensation model``).

This script prints the predicted downward push on a follower under a hovering leader, along the
axis and off it, and with ``--onnx FILE`` exports the model (``aerodock export``'s graph: inputs
``x`` and ``leader_R``, output ``f_ext_mps2``) and runs the file with onnxruntime beside NumPy.

    python examples/deploy_predictor.py --model out/model
    python examples/deploy_predictor.py --model out/model --onnx out/model.onnx --json

Needs nothing beyond NumPy to predict; ``aerodock[export]`` (onnx, onnxruntime) for ``--onnx``.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

from aerodock.learning.runtime import Predictor

DEPTHS_M = (0.3, 0.4, 0.6, 0.9, 1.2)
"""Depths of the follower below the leader, m."""
RADII_M = (0.0, 0.1, 0.3)
"""Horizontal distances of the follower from the leader's axis, m."""


def hover_scenes(depths_m: tuple[float, ...] = DEPTHS_M,
                 radii_m: tuple[float, ...] = RADII_M) -> tuple[np.ndarray, np.ndarray]:
    """Both vehicles at rest, the leader level, the follower at every (depth, radius): the
    model's inputs ``x`` (n, 9) and ``leader_R`` (n, 3, 3), depth-major."""
    grid = [(r, 0.0, d) for d in depths_m for r in radii_m]  # dp = (north, east, down)
    x = np.zeros((len(grid), 9))
    x[:, :3] = grid
    return x, np.tile(np.eye(3), (len(grid), 1, 1))


def onnx_check(model_dir: Path, out: Path, x: np.ndarray, leader_R: np.ndarray,
               numpy_pred: np.ndarray) -> dict[str, Any]:
    """Export ``model_dir`` to ``out`` (float32; checked by aerodock against NumPy before it
    takes the name) and run it here with onnxruntime on ``x``: the largest difference."""
    import onnxruntime as ort

    from aerodock.deploy.export import export_checked

    path, _ = export_checked(model_dir, out, dtype="float32")
    session = ort.InferenceSession(str(path), providers=["CPUExecutionProvider"])
    (pred,) = session.run(["f_ext_mps2"], {"x": x.astype(np.float32),
                                            "leader_R": leader_R.astype(np.float32)})
    return {"onnx": str(path), "max_abs_diff_vs_numpy_mps2": float(np.max(np.abs(
        pred - numpy_pred)))}


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Load, predict, optionally export; print (and return) the result."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", type=Path, required=True, help="trained model DIR")
    parser.add_argument("--onnx", type=Path, default=None, help="also export to this file")
    parser.add_argument("--json", action="store_true", help="print the result as JSON")
    args = parser.parse_args(argv)
    predictor = Predictor.load(args.model)
    x, leader_R = hover_scenes()
    pred = predictor.predict(x, leader_R)  # (n, 3), m/s², NED
    down = pred[:, 2].reshape(len(DEPTHS_M), len(RADII_M))
    result: dict[str, Any] = {
        "model": str(args.model), "kind": predictor.kind, "depths_m": list(DEPTHS_M),
        "radii_m": list(RADII_M), "accel_down_mps2": down.tolist()}
    if args.onnx is not None:
        result.update(onnx_check(args.model, args.onnx, x, leader_R, pred))
    if args.json:
        print(json.dumps(result))
        return result
    print(f"{predictor.kind} model, the wake's downward push on a follower under a hovering "
          "leader, m/s²")
    print("depth m | " + " | ".join(f"{r:.1f} m off axis" for r in RADII_M))
    for depth, row in zip(DEPTHS_M, down, strict=True):
        print(f"{depth:7.1f} | " + " | ".join(f"{v:+14.2f}" for v in row))
    if "onnx" in result:
        print(f"wrote {result['onnx']} (onnxruntime against NumPy: max difference "
              f"{result['max_abs_diff_vs_numpy_mps2']:.1e} m/s²)")
    return result


if __name__ == "__main__":
    try:
        main(sys.argv[1:])
    except ImportError:
        print("error: --onnx needs onnx and onnxruntime: pip install 'aerodock[export]'",
              file=sys.stderr)
        sys.exit(2)
    except (ValueError, OSError, RuntimeError) as err:  # a missing or damaged model: one line
        print(f"error: {' '.join(str(err).split())}", file=sys.stderr)
        sys.exit(2)
