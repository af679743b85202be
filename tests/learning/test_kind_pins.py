"""Every existing kind predicts bit for bit what it did before the kinds became a registry.

``data/kind_pins`` holds a small model folder per kind and the predictions of each path, written
by ``data/make_kind_pins.py`` with the code before the registry (commit ``ea3179b``): the
batched and the one-sample NumPy runtime, the NumPy and torch feature maps, and the torch module.
Their last bits are the machine's (NumPy's products and SIMD functions, PyTorch's kernels):
``KIND_pins.KEY.npz`` holds the same code's predictions from the stored folders and scenes on
the machine ``KEY`` (``tests/numerics_key.py`` with PyTorch's operations; ``PYTHONPATH=<ea3179b
tree> python tests/learning/data/make_kind_pins.py --keyed``). On a machine with no copy of its
own the pins are held to 1e-12 of each array's largest (4e-16 between the two machines
recorded).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from numerics_key import differing, load_golden

from aerodock.learning.features import feature_map
from aerodock.learning.runtime import Predictor

PINS = Path(__file__).parent / "data" / "kind_pins"
PINNED_KINDS = ("so2", "so2-ext", "so2-wrench", "so2-leader", "so2-pair", "mlp")
LEADER_AWARE = ("so2-leader", "so2-pair")


@pytest.fixture(scope="module")
def scenes() -> dict[str, np.ndarray]:
    with np.load(PINS / "scenes.npz") as data:
        return {k: data[k] for k in data.files}


def _pins(kind: str) -> tuple[dict[str, np.ndarray], bool]:
    """The kind's pins and whether this machine wrote them (``numerics_key.load_golden``)."""
    return load_golden(PINS / f"{kind}_pins.npz", torch=True)


def _same(got: np.ndarray, pins: tuple[dict[str, np.ndarray], bool], name: str) -> bool:
    """``got`` is the pin ``name``: bit for bit on the machine that wrote this copy, else to
    1e-12 of its largest."""
    arrays, exact = pins
    return not differing({name: np.asarray(got)}, arrays, exact, rtol=1e-12)


@pytest.mark.parametrize("kind", PINNED_KINDS)
def test_numpy_runtime_predicts_bit_for_bit(kind, scenes):
    x, rot = scenes["x"], scenes["rot"]
    ws = scenes["scales"] if kind in LEADER_AWARE else None
    pins = _pins(kind)
    pred = Predictor.load(PINS / kind)
    force, torque = pred.predict_wrench(x, rot, ws)
    assert _same(force, pins, "force")
    if "torque" in pins[0]:
        assert _same(torque, pins, "torque")
    else:
        assert torque is None
    one = np.stack([pred.predict_one(x[j], rot[j], None if ws is None else ws[j])
                    for j in range(x.shape[0])])
    assert _same(one, pins, "one")


@pytest.mark.parametrize("kind", PINNED_KINDS)
def test_feature_maps_bit_for_bit(kind, scenes):
    torch = pytest.importorskip("torch")
    from aerodock.learning.features import feature_map_torch

    x, rot = scenes["x"], scenes["rot"]
    ws = scenes["scales"] if kind in LEADER_AWARE else None
    pins = _pins(kind)
    z, m = feature_map(kind, x, rot, wake_scales=ws)
    assert _same(z, pins, "z") and _same(m, pins, "m")
    zt, mt = feature_map_torch(kind, torch.as_tensor(x), torch.as_tensor(rot),
                               wake_scales=None if ws is None else torch.as_tensor(ws))
    assert _same(zt.numpy(), pins, "torch_z")
    assert _same(mt.numpy(), pins, "torch_m")


@pytest.mark.parametrize("kind", PINNED_KINDS)
def test_torch_module_bit_for_bit(kind, scenes):
    torch = pytest.importorskip("torch")
    from aerodock.learning.models import load_torch_model

    x, rot = scenes["x"], scenes["rot"]
    ws = scenes["scales"] if kind in LEADER_AWARE else None
    pins = _pins(kind)
    model = load_torch_model(PINS / kind).double()
    with torch.no_grad():
        force, torque = model.wrench(torch.as_tensor(x), torch.as_tensor(rot),
                                     None if ws is None else torch.as_tensor(ws))
    assert _same(force.numpy(), pins, "torch_force")
    if "torch_torque" in pins[0]:
        assert _same(torque.numpy(), pins, "torch_torque")


@pytest.mark.parametrize("kind", PINNED_KINDS)
def test_a_samples_prediction_does_not_depend_on_its_batch(kind, scenes):
    """The batched path predicts each sample to the bit alike in batches of 1 to 17 and of all
    48 (NumPy's products round a row otherwise in a batch of one or in a block's leftover rows;
    the runtime pads the batch: ``aerodock.learning.runtime.ROW_BLOCK``)."""
    x, rot = scenes["x"], scenes["rot"]
    ws = scenes["scales"] if kind in LEADER_AWARE else None
    pred = Predictor.load(PINS / kind)
    force, torque = pred.predict_wrench(x, rot, ws)
    for m in range(1, 18):
        parts = [pred.predict_wrench(x[i:i + m], rot[i:i + m], None if ws is None else ws[i:i + m])
                 for i in range(0, x.shape[0], m)]
        assert np.array_equal(np.concatenate([f for f, _ in parts]), force), m
        if torque is not None:
            assert np.array_equal(np.concatenate([t for _, t in parts]), torque), m
