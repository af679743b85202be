"""Write the pinned model folders and predictions of ``test_kind_pins.py`` (run once, by hand).

Run at the commit before the model-kind registry (``ea3179b``) to pin what the old code
predicted: ``PYTHONPATH=. python tests/learning/data/make_kind_pins.py``. Each kind gets a small
randomly initialised model folder (hidden 8x8, a normalisation from real features) and the
predictions of every path: the batched and one-sample NumPy runtime, the NumPy and torch
feature maps, and the torch module (float64). ``--keyed``: only this machine's copy of the
predictions, from the stored folders (``test_kind_pins.py``'s docstring).
"""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

import numpy as np
import torch

from aerodock.geometry import euler_to_rotmat
from aerodock.learning.features import feature_map, feature_map_torch
from aerodock.learning.modelfile import save_model_dir
from aerodock.learning.models import build_model, load_torch_model
from aerodock.learning.runtime import Predictor

HERE = Path(__file__).parent / "kind_pins"
PINNED_KINDS = ("so2", "so2-ext", "so2-wrench", "so2-leader", "so2-pair", "mlp")


def scenes(n: int = 48) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Scenes below a tilted, yawed leader (the last two on its axis and at rest)."""
    rng = np.random.default_rng(20261205)
    x = np.concatenate([rng.uniform([-0.6, -0.6, 0.2], [0.6, 0.6, 1.6], (n, 3)),
                        rng.normal(0, 0.4, (n, 6))], axis=1)
    x[-2, :2] = 0.0
    x[-1, :] = [0.0, 0.0, 0.5, 0, 0, 0, 0, 0, 0]
    rot = euler_to_rotmat(rng.normal(0, 0.1, n), rng.normal(0, 0.1, n), rng.uniform(-3, 3, n))
    scales = np.stack([rng.uniform(3, 8, n), rng.uniform(0.04, 0.2, n), rng.uniform(3, 8, n),
                       rng.uniform(0.04, 0.2, n)], axis=1)
    return x, rot, scales


def predictions(kind: str, folder: Path, x: np.ndarray, rot: np.ndarray,
                scales: np.ndarray) -> dict[str, np.ndarray]:
    """Every path's predictions of the model in ``folder`` for the scenes."""
    ws = scales if kind in ("so2-leader", "so2-pair") else None
    pred = Predictor.load(folder)
    force, torque = pred.predict_wrench(x, rot, ws)
    one = np.stack([pred.predict_one(x[j], rot[j], None if ws is None else ws[j])
                    for j in range(x.shape[0])])
    mod = load_torch_model(folder).double()
    tw = None if ws is None else torch.as_tensor(ws)
    with torch.no_grad():
        tforce, ttorque = mod.wrench(torch.as_tensor(x), torch.as_tensor(rot), tw)
        zt, mt = feature_map_torch(kind, torch.as_tensor(x), torch.as_tensor(rot),
                                   wake_scales=tw)
    z, m = feature_map(kind, x, rot, wake_scales=ws)
    arrays = {"force": force, "one": one, "torch_force": tforce.numpy(),
              "z": z, "m": np.asarray(m), "torch_z": zt.numpy(), "torch_m": mt.numpy()}
    if torque is not None:
        arrays["torque"] = torque
        arrays["torch_torque"] = ttorque.numpy()
    return arrays


def main() -> None:
    x, rot, scales = scenes()
    if HERE.exists():
        shutil.rmtree(HERE)
    HERE.mkdir()
    np.savez(HERE / "scenes.npz", x=x, rot=rot, scales=scales)
    for i, kind in enumerate(PINNED_KINDS):
        torch.manual_seed(100 + i)
        model = build_model(kind, hidden=(8, 8))
        ws = scales if kind in ("so2-leader", "so2-pair") else None
        z, _ = feature_map(kind, x, rot, wake_scales=ws)
        out = np.random.default_rng(i).normal(0.5, 2.0, (x.shape[0], model.layer_sizes[-1]))
        model.set_normalisation(z, out)
        model.eval()
        folder = save_model_dir(HERE / kind, model.spec(), model.weights(),
                                training={"pinned": True})
        arrays = predictions(kind, folder, x, rot, scales)
        np.savez(HERE / f"{kind}_pins.npz", **arrays)
        print(kind, {k: v.shape for k, v in arrays.items()})


def keyed() -> None:
    """This machine's copy of the pins (``KIND_pins.KEY.npz``): the stored folders' predictions
    for the stored scenes, by the code on the path, ``KEY`` this machine's numerics."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # tests/, for numerics_key
    from numerics_key import numerics_key

    key = numerics_key(torch=True)
    with np.load(HERE / "scenes.npz") as data:
        x, rot, scales = data["x"], data["rot"], data["scales"]
    for kind in PINNED_KINDS:
        np.savez(HERE / f"{kind}_pins.{key}.npz", **predictions(kind, HERE / kind, x, rot, scales))
        print(kind, key)


if __name__ == "__main__":
    keyed() if "--keyed" in sys.argv else main()
