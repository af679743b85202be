"""Every kind of the registry, whatever it is: its NumPy, torch and ONNX predictions agree, a
model file of it round-trips, and it is SO(2)-equivariant where it says so.

Parametrised over :data:`aerodock.learning.kinds.REGISTRY`: a kind added to the registry is
tested here without a line of its own.
"""

from __future__ import annotations

import numpy as np
import pytest

from aerodock.geometry import euler_to_rotmat, rot_z
from aerodock.learning.features import feature_map
from aerodock.learning.kinds import KINDS, REGISTRY, get_kind
from aerodock.learning.runtime import Predictor

torch = pytest.importorskip("torch")

N = 40


def _scenes(seed: int = 1) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Scenes below a tilted, yawed leader, and a Crazyflie-like pair's wake scales (the last
    scene on the leader's axis, at rest)."""
    rng = np.random.default_rng(seed)
    x = np.concatenate([rng.uniform([-0.5, -0.5, 0.2], [0.5, 0.5, 1.5], (N, 3)),
                        rng.normal(0, 0.4, (N, 6))], axis=1)
    x[-1] = [0, 0, 0.6, 0, 0, 0, 0, 0, 0]
    rot = euler_to_rotmat(rng.normal(0, 0.15, N), rng.normal(0, 0.15, N), rng.uniform(-3, 3, N))
    scales = np.stack([rng.uniform(3, 8, N), rng.uniform(0.04, 0.2, N), rng.uniform(3, 8, N),
                       rng.uniform(0.04, 0.2, N)], axis=1)
    return x, rot, scales


def _model(name: str):
    """A randomly initialised model of kind ``name`` with a normalisation from its features."""
    from aerodock.learning.models import build_model

    kind = get_kind(name)
    torch.manual_seed(KINDS.index(name))
    model = build_model(name, hidden=(16, 16))
    if kind.has_network:
        x, rot, scales = _scenes(2)
        z, _ = feature_map(name, x, rot, wake_scales=scales if kind.n_wake_scales else None)
        out = np.random.default_rng(3).normal(0.3, 1.5, (N, kind.n_outputs))
        model.set_normalisation(z, out)
    return model.eval()


def _scales_for(name: str, scales: np.ndarray) -> np.ndarray | None:
    k = get_kind(name).n_wake_scales
    return scales[:, :k] if k else None


@pytest.mark.parametrize("name", KINDS)
def test_numpy_torch_and_onnx_agree(name, tmp_path):
    from aerodock.deploy.export import (
        OUTPUT_NAME,
        SCALES_INPUT_NAME,
        TORQUE_OUTPUT_NAME,
        build_onnx,
    )

    ort = pytest.importorskip("onnxruntime")
    kind = get_kind(name)
    model = _model(name)
    x, rot, scales = _scenes()
    ws = _scales_for(name, scales)
    pred = Predictor.load(_save(model, tmp_path / name))
    force, torque = pred.predict_wrench(x, rot, ws)
    one = np.stack([pred.predict_one(x[j], rot[j], None if ws is None else ws[j])
                    for j in range(N)])
    with torch.no_grad():
        tws = None if ws is None else torch.as_tensor(ws)
        if kind.has_network:
            tforce, ttorque = model.double().wrench(torch.as_tensor(x), torch.as_tensor(rot), tws)
        else:
            tforce, ttorque = model(torch.as_tensor(x), torch.as_tensor(rot), tws), None
    proto = build_onnx(model.spec(), model.weights(), dtype="float64")
    sess = ort.InferenceSession(proto.SerializeToString(), providers=["CPUExecutionProvider"])
    feeds = {"x": x, "leader_R": rot}
    if ws is not None:
        feeds[SCALES_INPUT_NAME] = ws
    got = dict(zip([o.name for o in sess.get_outputs()], sess.run(None, feeds), strict=True))
    assert np.abs(force).max() > 0.1 or not kind.has_network  # not a trivially zero model
    for other in (one, tforce.numpy(), got[OUTPUT_NAME]):
        np.testing.assert_allclose(other, force, rtol=1e-9, atol=1e-9)
    assert (torque is not None) == kind.torque == (TORQUE_OUTPUT_NAME in got)
    if kind.torque:
        np.testing.assert_allclose(ttorque.numpy(), torque, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(got[TORQUE_OUTPUT_NAME], torque, rtol=1e-9, atol=1e-9)


def _save(model, path):
    from aerodock.learning.modelfile import save_model_dir

    return save_model_dir(path, model.spec(), model.weights())


def _about_axis(rot: np.ndarray, theta: float) -> np.ndarray:
    """World rotation by ``theta`` about the leader's axis a3: ``Q = R Rz(theta) R^T``."""
    return rot @ rot_z(np.array(theta)) @ rot.T


@pytest.mark.parametrize("name", [k for k, v in REGISTRY.items()
                                  if v.equivariant and v.has_network])
@pytest.mark.parametrize("theta", [0.7, -2.4])
def test_equivariant_kinds_rotate_their_prediction_with_the_scene(name, theta):
    """The whole scene (positions, velocities, the leader's attitude) rotated about the leader's
    axis: the prediction (and a torque kind's torque) rotates with it."""
    model = _model(name)
    pred = Predictor(model.spec(), model.weights())
    x, rot, scales = _scenes(4)
    ws = _scales_for(name, scales)
    q = np.stack([_about_axis(r, theta) for r in rot])
    x_rot = np.concatenate([np.einsum("nij,nj->ni", q, x[:, k:k + 3]) for k in (0, 3, 6)], 1)
    force, torque = pred.predict_wrench(x, rot, ws)
    force_rot, torque_rot = pred.predict_wrench(x_rot, q @ rot, ws)
    np.testing.assert_allclose(force_rot, np.einsum("nij,nj->ni", q, force), atol=1e-9)
    if torque is not None:
        np.testing.assert_allclose(torque_rot, np.einsum("nij,nj->ni", q, torque), atol=1e-9)
    assert not np.allclose(force_rot, force, atol=1e-3)  # the rotation did move it


@pytest.mark.parametrize("name", [k for k, v in REGISTRY.items() if not v.equivariant])
def test_kinds_that_claim_no_equivariance_break_it(name):
    """A kind that does not claim SO(2) equivariance (the world-frame MLP) is not made so by
    accident: rotating the scene does not just rotate its prediction."""
    model = _model(name)
    pred = Predictor(model.spec(), model.weights())
    x, rot, scales = _scenes(4)
    q = np.stack([_about_axis(r, 1.1) for r in rot])
    x_rot = np.concatenate([np.einsum("nij,nj->ni", q, x[:, k:k + 3]) for k in (0, 3, 6)], 1)
    ws = _scales_for(name, scales)
    rotated = np.einsum("nij,nj->ni", q, pred.predict(x, rot, ws))
    assert not np.allclose(pred.predict(x_rot, q @ rot, ws), rotated, atol=1e-3)


@pytest.mark.parametrize("name", KINDS)
def test_a_kinds_model_file_round_trips_exactly(name, tmp_path):
    """Saved and loaded, a model of every kind predicts exactly what its in-memory predictor
    does, and the file names the kind's features and outputs."""
    import json

    model = _model(name)
    x, rot, scales = _scenes(5)
    ws = _scales_for(name, scales)
    folder = _save(model, tmp_path / "m")
    doc = json.loads((folder / "model.json").read_text())
    kind = get_kind(name)
    assert doc["kind"] == name
    if kind.has_network:
        assert doc["features"]["names"] == list(kind.feature_names)
        assert doc["outputs"] == list(kind.output_names)
        assert doc["layer_sizes"][0] == kind.n_features
    in_memory = Predictor(model.spec(), model.weights()) if kind.has_network else None
    loaded = Predictor.load(folder)
    if in_memory is not None:
        assert np.array_equal(loaded.predict(x, rot, ws), in_memory.predict(x, rot, ws))
    else:
        assert np.array_equal(loaded.predict(x, rot), np.zeros((N, 3)))


def test_an_unknown_kind_is_refused_by_the_config_and_the_model_file(tmp_path):
    from aerodock.config import ConfigError, load_config
    from aerodock.learning.modelfile import ModelFileError, load_model_dir, model_checksum

    bad = tmp_path / "bad.toml"
    bad.write_text('[curriculum]\nmodel = "so2-bogus"\n')
    with pytest.raises(ConfigError, match="curriculum.model"):
        load_config(bad)
    for name in REGISTRY:
        if REGISTRY[name].has_network:
            cfg = tmp_path / f"{name}.toml"
            cfg.write_text(f'[curriculum]\nmodel = "{name}"\n')
            assert load_config(cfg).curriculum.model == name
    import json

    folder = _save(_model("so2"), tmp_path / "m")
    doc = json.loads((folder / "model.json").read_text())
    doc["kind"] = "so2-bogus"
    doc["model_sha256"] = model_checksum(doc)
    (folder / "model.json").write_text(json.dumps(doc))
    with pytest.raises(ModelFileError, match="unknown model kind 'so2-bogus'"):
        load_model_dir(folder)


def test_the_template_kind_runs_everywhere_once_registered(tmp_path, monkeypatch):
    """``kinds/template.py`` is a working kind: registered (its one line), NumPy, torch and
    ONNX agree on it and it is equivariant, with no other change anywhere."""
    from aerodock.learning.kinds.template import KIND

    assert KIND.name not in REGISTRY
    monkeypatch.setitem(REGISTRY, KIND.name, KIND)
    monkeypatch.setattr("aerodock.learning.kinds.KINDS", (*KINDS, KIND.name))
    monkeypatch.setattr(__name__ + ".KINDS", (*KINDS, KIND.name))
    test_numpy_torch_and_onnx_agree(KIND.name, tmp_path)
    test_equivariant_kinds_rotate_their_prediction_with_the_scene(KIND.name, 0.9)
