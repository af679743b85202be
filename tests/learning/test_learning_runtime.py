"""NumPy runtime vs torch, model files (round trip and corruption), ONNX export."""

from __future__ import annotations

import io
import json
import subprocess
import sys

import numpy as np
import pytest
import torch

from aerodock.deploy.export import check_onnx, export_onnx
from aerodock.downwash.base import BodyState
from aerodock.geometry import euler_to_rotmat
from aerodock.learning.modelfile import (
    CHECKSUM_KEY,
    ModelFileError,
    load_model_dir,
    model_checksum,
)
from aerodock.learning.models import build_model, load_torch_model
from aerodock.learning.runtime import Predictor, ZeroPredictor, load_predictor
from aerodock.learning.train import TrainedModel


def _inputs(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    x = np.concatenate([rng.uniform(-0.8, 0.8, (n, 2)), rng.uniform(-0.2, 1.8, (n, 1)),
                        rng.normal(0, 0.4, (n, 6))], axis=1)
    rot = euler_to_rotmat(rng.normal(0, 0.15, n), rng.normal(0, 0.15, n), rng.uniform(-3, 3, n))
    return x, rot


def _random_trained(kind: str, spectral_norm: bool = False, activation: str = "tanh"):
    torch.manual_seed(11)
    model = build_model(kind, spectral_norm=spectral_norm, activation=activation)
    if kind != "zero":
        rng = np.random.default_rng(2)
        k = 2 if kind == "so2" else 3
        model.set_normalisation(rng.normal(0.3, 0.7, (40, model.layer_sizes[0])),
                                rng.normal(0.5, 2.0, (40, k)))
        if spectral_norm:  # a few training-mode passes so the power iteration has run
            model.train()
            x, rot = _inputs(8)
            for _ in range(3):
                model(torch.as_tensor(x, dtype=torch.float32),
                      torch.as_tensor(rot, dtype=torch.float32))
    model.eval()
    return TrainedModel(kind, model, {"note": "random"})


CASES = [("so2", False, "tanh"), ("so2-ext", False, "tanh"), ("mlp", False, "tanh"),
         ("so2", True, "tanh"), ("so2-ext", False, "silu")]


@pytest.mark.parametrize(("kind", "sn", "act"), CASES)
def test_runtime_equals_torch(tmp_path, kind, sn, act):
    trained = _random_trained(kind, sn, act)
    x, rot = _inputs(300)
    want32 = trained.predict(x, rot)  # float32 torch
    pred = Predictor.load(trained.save(tmp_path / kind))
    got = pred.predict(x, rot)
    np.testing.assert_allclose(got, want32, atol=1e-5)
    with torch.no_grad():  # the stored weights, run by torch in float64: agreement to rounding
        model64 = load_torch_model(tmp_path / kind).double()
        want64 = model64(torch.as_tensor(x), torch.as_tensor(rot)).numpy()
    np.testing.assert_allclose(got, want64, atol=1e-10)
    single = np.stack([pred.predict_one(x[i], rot[i]) for i in range(50)])
    np.testing.assert_allclose(single, want32[:50], atol=1e-5)
    np.testing.assert_allclose(single, got[:50], atol=1e-12)


def test_trained_model_runtime_equals_torch(tmp_path, trained_so2, synth_ds):
    pred = Predictor.load(trained_so2.save(tmp_path / "m"))
    sub = synth_ds.subset(np.arange(0, synth_ds.n, 7))
    want = trained_so2.predict(sub.x, sub.leader_R)
    np.testing.assert_allclose(pred.predict(sub.x, sub.leader_R), want, atol=1e-5)
    np.testing.assert_allclose(pred.predict_one(sub.x[3], sub.leader_R[3]), want[3], atol=1e-5)


def test_predict_bodies_matches_predict():
    trained = _random_trained("so2-ext")
    pred = trained.predictor()
    x, rot = _inputs(5)
    lp = np.random.default_rng(1).normal(size=(5, 3))

    def bodies(sl):
        n = len(lp[sl])
        ones = np.ones(n)
        leader = BodyState(p=lp[sl], v=x[sl, 3:6], R=rot[sl], thrust_n=7 * ones, mass_kg=ones)
        follower = BodyState(p=lp[sl] + x[sl, 0:3], v=x[sl, 6:9], R=np.tile(np.eye(3), (n, 1, 1)),
                             thrust_n=7 * ones, mass_kg=ones)
        return leader, follower

    want = pred.predict(x, rot)
    np.testing.assert_allclose(pred.predict_bodies(*bodies(slice(None))), want, atol=1e-12)
    np.testing.assert_allclose(pred.predict_bodies(*bodies(slice(2, 3))), want[2:3], atol=1e-12)
    zero = ZeroPredictor()
    assert zero.predict_bodies(*bodies(slice(None))).shape == (5, 3)
    assert not zero.predict(x, rot).any() and not zero.predict_one(x[0], rot[0]).any()


def test_zero_model_round_trip(tmp_path):
    path = _random_trained("zero").save(tmp_path / "zero")
    pred = Predictor.load(path)
    assert isinstance(pred, ZeroPredictor) and pred.kind == "zero"
    assert isinstance(load_predictor(None), ZeroPredictor)
    x, rot = _inputs(4)
    assert pred.predict(x, rot).shape == (4, 3)


def test_importing_runtime_does_not_import_torch(tmp_path):
    path = _random_trained("so2").save(tmp_path / "m")
    code = (
        "import sys, numpy as np\n"
        "import aerodock.learning.runtime as rt\n"
        f"p = rt.Predictor.load({str(path)!r})\n"
        "p.predict_one(np.array([0.1, 0, 0.5, 0, 0, 0, 0, 0, 0.]), np.eye(3))\n"
        "assert 'torch' not in sys.modules, 'torch was imported'\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=60)
    assert proc.returncode == 0, proc.stderr


# -- model files: corrupt or mismatched ------------------------------------------------------

def _write_doc(path, doc, reseal=True):
    """Write a model.json; ``reseal`` recomputes its checksum, so the checks behind it (what a
    version 1 file or a deliberately re-sealed one meets) are reached."""
    if reseal:
        doc = {k: v for k, v in doc.items() if k != CHECKSUM_KEY}
        doc[CHECKSUM_KEY] = model_checksum(doc)
    (path / "model.json").write_text(json.dumps(doc))


def _edit_json(path, **changes):
    doc = json.loads((path / "model.json").read_text())
    for key, value in changes.items():
        if value is _DELETE:
            doc.pop(key)
        else:
            doc[key] = value
    _write_doc(path, doc)


_DELETE = object()


def _write_weights(path, arrays, update_hash=True):
    import hashlib

    buf = io.BytesIO()
    np.savez(buf, **arrays)
    (path / "weights.npz").write_bytes(buf.getvalue())
    if update_hash:
        doc = json.loads((path / "model.json").read_text())
        doc["weights"]["sha256"] = hashlib.sha256(buf.getvalue()).hexdigest()
        _write_doc(path, doc)


def _corruptions():
    def garbage_json(p):
        (p / "model.json").write_text("{not json")

    def no_json(p):
        (p / "model.json").unlink()

    def truncated_weights(p):
        blob = (p / "weights.npz").read_bytes()
        (p / "weights.npz").write_bytes(blob[: len(blob) // 2])

    def truncated_weights_no_hash(p):
        truncated_weights(p)
        doc = json.loads((p / "model.json").read_text())
        doc["weights"]["sha256"] = None
        _write_doc(p, doc)

    def no_weights(p):
        (p / "weights.npz").unlink()

    def wrong_shape(p):
        with np.load(p / "weights.npz") as d:
            arrays = {k: d[k] for k in d.files}
        arrays["W1"] = arrays["W1"][:, :-1]
        _write_weights(p, arrays)

    def missing_array(p):
        with np.load(p / "weights.npz") as d:
            arrays = {k: d[k] for k in d.files if k != "b2"}
        _write_weights(p, arrays)

    def nan_weights(p):
        with np.load(p / "weights.npz") as d:
            arrays = {k: d[k] for k in d.files}
        arrays["W0"][0, 0] = np.nan
        _write_weights(p, arrays)

    def pickled_weights(p):
        with np.load(p / "weights.npz") as d:
            arrays = {k: d[k] for k in d.files}
        arrays["W0"] = np.array([{"evil": 1}], dtype=object)
        _write_weights(p, arrays)

    def other_models_weights(p):
        with np.load(p / "weights.npz") as d:
            arrays = {k: d[k] * 2 for k in d.files}
        _write_weights(p, arrays, update_hash=False)

    return {
        "garbage json": (garbage_json, "model.json"),
        "no json": (no_json, "model.json"),
        "wrong format": (lambda p: _edit_json(p, format="something-else"), "not an aerodock"),
        "newer version": (lambda p: _edit_json(p, version=99), "newer"),
        "unknown kind": (lambda p: _edit_json(p, kind="transformer"), "unknown model kind"),
        "kind mismatch": (lambda p: _edit_json(p, kind="so2-ext"), "do not fit"),
        "feature version": (lambda p: _edit_json(p, feature_version=0), "feature version"),
        "activation": (lambda p: _edit_json(p, activation="relu6"), "activation"),
        "units": (lambda p: _edit_json(p, units="g ENU"), "units"),
        "normalisation": (lambda p: _edit_json(p, normalisation={"in_mean": [0.0]}),
                          "normalisation"),
        "no layer sizes": (lambda p: _edit_json(p, layer_sizes=_DELETE), "layer_sizes"),
        "truncated weights": (truncated_weights, "weights.npz"),
        "truncated weights, no hash": (truncated_weights_no_hash, "sha256 missing"),
        "no hash": (lambda p: _edit_json(p, weights={"file": "weights.npz"}), "sha256 missing"),
        "no weights": (no_weights, "weights.npz"),
        "wrong shape": (wrong_shape, "W1 has shape"),
        "missing array": (missing_array, "b2 missing"),
        "nan weights": (nan_weights, "finite"),
        "pickled weights": (pickled_weights, "weights.npz"),
        "other model's weights": (other_models_weights, "SHA-256"),
    }


@pytest.mark.parametrize("case", list(_corruptions()))
def test_corrupt_model_files_give_model_file_error(tmp_path, case):
    corrupt, match = _corruptions()[case]
    path = _random_trained("so2").save(tmp_path / "m")
    load_model_dir(path)  # fine before
    corrupt(path)
    with pytest.raises(ModelFileError, match=match) as err:
        Predictor.load(path)
    msg = str(err.value)
    assert "\n" not in msg and str(tmp_path) in msg
    assert isinstance(err.value, ValueError)


def test_missing_model_dir(tmp_path):
    with pytest.raises(ModelFileError, match="not found"):
        Predictor.load(tmp_path / "nope")


def test_model_json_metadata(tmp_path, trained_so2):
    path = trained_so2.save(tmp_path / "m")
    doc = json.loads((path / "model.json").read_text())
    assert doc["kind"] == "so2" and doc["units"] == "m/s^2 NED"
    assert doc["layer_sizes"] == [6, 64, 64, 2] and doc["activation"] == "tanh"
    assert doc["training"]["data"]["n_samples"] == 12000
    assert doc["training"]["val_loss"] > 0 and doc["training"]["train_time_s"] > 0
    for key in ("in_mean", "in_std", "out_mean", "out_std"):
        assert len(doc["normalisation"][key]) in (6, 2)
    with np.load(path / "weights.npz", allow_pickle=False) as data:
        assert all(data[k].dtype == np.float32 for k in data.files)
    # saving again over an existing model replaces it cleanly (no temp files left behind)
    trained_so2.save(path)
    assert sorted(p.name for p in path.iterdir()) == ["model.json", "weights.npz"]


# -- writing a model directory as a whole ---------------------------------------------------

def _weights_of(path):
    with np.load(path / "weights.npz") as data:
        return {k: data[k].copy() for k in data.files}


def test_failed_save_keeps_the_old_model_and_leaves_no_temp(tmp_path, monkeypatch):
    import builtins

    path = _random_trained("so2").save(tmp_path / "m")
    before = (path / "model.json").read_bytes(), (path / "weights.npz").read_bytes()
    real_open = builtins.open
    calls = []

    def failing_open(file, mode="r", *args, **kwargs):  # the second file cannot be written
        if "w" in str(mode) and str(file).endswith("model.json"):
            calls.append(file)
            raise OSError(28, "No space left on device")
        return real_open(file, mode, *args, **kwargs)

    monkeypatch.setattr(builtins, "open", failing_open)
    with pytest.raises(OSError, match="No space"):
        _random_trained("so2-ext").save(path)
    monkeypatch.undo()
    assert calls
    assert ((path / "model.json").read_bytes(), (path / "weights.npz").read_bytes()) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m"]
    Predictor.load(path)


def test_save_refuses_a_directory_with_other_files(tmp_path):
    (tmp_path / "m").mkdir()
    (tmp_path / "m" / "notes.txt").write_text("mine")
    with pytest.raises(ValueError, match="notes.txt"):
        _random_trained("so2").save(tmp_path / "m")
    assert (tmp_path / "m" / "notes.txt").read_text() == "mine"


# The writer of a model directory (TrainedModel.save's), looping over two models: only the
# model file module is imported (no PyTorch, no test module), so the process is ready at once.
_SAVE_LOOP = """
import pickle
from aerodock.learning.modelfile import save_model_dir
with open({models!r}, "rb") as fh:
    models = pickle.load(fh)
print("ready", flush=True)
i = 0
while True:
    spec, weights, info = models[i % 2]
    save_model_dir({path!r}, spec, weights, training=info)
    i += 1
"""


@pytest.mark.slow
def test_kill_during_saves_leaves_a_whole_model(tmp_path):
    """kill -9 at random moments of repeated saves: the directory always holds one whole model
    (weights matching model.json), one of the two being written, and no mix."""
    import os
    import pickle
    import signal
    import time

    path = tmp_path / "m"
    first = _random_trained("so2")
    first.save(path)
    want = {json.dumps({k: v.tolist() for k, v in sorted(_weights_of(path).items())})}
    doubled = _random_trained("so2")
    with torch.no_grad():
        for p in doubled.model.parameters():
            p.mul_(2.0)
    with open(tmp_path / "models.pkl", "wb") as fh:  # the doubled one first, then the first
        pickle.dump([(m.model.spec(), m.model.weights(), m.info) for m in (doubled, first)], fh)
    code = _SAVE_LOOP.format(models=str(tmp_path / "models.pkl"), path=str(path))
    rng = np.random.default_rng(5)
    for _ in range(6):
        proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
        assert proc.stdout.readline().strip() == "ready"
        time.sleep(float(rng.uniform(0.05, 0.4)))
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
        spec, weights, doc = load_model_dir(path)  # checksum verified: no mix
        assert sorted(p.name for p in path.iterdir()) == ["model.json", "weights.npz"]
        want.add(json.dumps({k: v.tolist() for k, v in sorted(_weights_of(path).items())}))
    assert len(want) <= 2  # only ever the first model or the doubled one


def test_model_records_its_vehicles_and_flags_others(tmp_path):
    from aerodock.config import load_config
    from aerodock.deploy.compatibility import model_vehicle_warnings
    from aerodock.learning.training_vehicles import vehicles_from_flights

    trained = _random_trained("so2")
    flights = [{"leader_mass_kg": 0.7, "follower_mass_kg": 0.7, "leader_rotor_radius_m": 0.0635,
                "follower_rotor_radius_m": 0.0635, "leader_n_rotors": 4, "follower_n_rotors": 4}]
    trained.info["data"] = {"vehicles": vehicles_from_flights(flights)}
    path = trained.save(tmp_path / "m")
    doc = json.loads((path / "model.json").read_text())
    assert doc["vehicles"]["follower"] == {"mass_kg": 0.7, "rotor_radius_m": 0.0635,
                                           "n_rotors": 4, "diagonal_m": None}
    assert doc["units"] == "m/s^2 NED"
    cfg = load_config()
    pred = Predictor.load(path)
    assert model_vehicle_warnings(pred, cfg) == []
    heavy = cfg.with_overrides({"vehicle": {"mass_kg": 1.5, "n_rotors": 6}})
    notes = model_vehicle_warnings(pred, heavy)
    assert any("leader mass_kg = 0.7, configured 1.5" in n for n in notes)
    assert any("follower n_rotors = 4, configured 6" in n for n in notes)
    # flights that disagree, or say nothing, are recorded as such
    mixed = vehicles_from_flights(flights + [{**flights[0], "follower_mass_kg": 0.5}])
    assert mixed["follower"]["mass_kg"] == [0.5, 0.7]
    unknown = vehicles_from_flights([{}])
    assert unknown["leader"] == {"mass_kg": None, "rotor_radius_m": None, "n_rotors": None,
                                 "diagonal_m": None}
    bare = _random_trained("so2").save(tmp_path / "bare")
    assert "does not record" in model_vehicle_warnings(Predictor.load(bare), cfg)[-1]


# -- ONNX ------------------------------------------------------------------------------------

@pytest.mark.parametrize("kind", ["so2", "so2-ext", "mlp", "zero"])
def test_onnx_export_matches_onnxruntime(tmp_path, kind):
    pytest.importorskip("onnxruntime")
    trained = _random_trained(kind)
    model_dir = trained.save(tmp_path / kind)
    onnx_path = export_onnx(model_dir, tmp_path / f"{kind}.onnx")
    pred = Predictor.load(model_dir)
    assert check_onnx(onnx_path, pred, n=300) < 1e-5
    if kind == "so2":  # a spectrally normalised TrainedModel exports directly (folded weights)
        sn = _random_trained("so2", spectral_norm=True)
        assert check_onnx(export_onnx(sn, tmp_path / "sn.onnx"), sn.predictor()) < 1e-5
    import onnx

    graph = onnx.load(str(onnx_path)).graph
    assert [i.name for i in graph.input] == ["x", "leader_R"]
    assert [o.name for o in graph.output] == ["f_ext_mps2"]
    # the torch module rebuilt from the files agrees too
    x, rot = _inputs(20)
    with torch.no_grad():
        again = load_torch_model(model_dir)(torch.as_tensor(x, dtype=torch.float32),
                                            torch.as_tensor(rot, dtype=torch.float32))
    np.testing.assert_allclose(again.numpy(), pred.predict(x, rot), atol=1e-5)


@pytest.mark.parametrize("kind", ["so2", "so2-ext", "mlp", "zero"])
def test_onnx_float64_equals_numpy_and_carries_metadata(tmp_path, kind):
    pytest.importorskip("onnxruntime")
    from aerodock.deploy.export import read_onnx_metadata
    from aerodock.learning.training_vehicles import vehicles_from_flights

    trained = _random_trained(kind, activation="silu" if kind == "so2-ext" else "tanh")
    trained.info["data"] = {"vehicles": vehicles_from_flights(
        [{"leader_mass_kg": 0.7, "follower_mass_kg": 0.5, "follower_n_rotors": 4}])}
    model_dir = trained.save(tmp_path / kind)
    pred = Predictor.load(model_dir)
    path64 = export_onnx(model_dir, tmp_path / f"{kind}64.onnx", dtype="float64")
    assert check_onnx(path64, pred, n=300) < 1e-10
    meta = read_onnx_metadata(path64)
    doc = json.loads((model_dir / "model.json").read_text())
    assert meta["aerodock.kind"] == kind and meta["aerodock.units"] == "m/s^2 NED"
    assert meta["aerodock.dtype"] == "float64"
    assert json.loads(meta["aerodock.vehicles"]) == doc["vehicles"]
    assert json.loads(meta["aerodock.vehicles"])["follower"]["mass_kg"] == 0.5
    if kind != "zero":
        assert meta["aerodock.weights_sha256"] == doc["weights"]["sha256"]
    import onnxruntime as ort

    sess = ort.InferenceSession(str(path64), providers=["CPUExecutionProvider"])
    x, rot = _inputs(7, seed=4)
    with pytest.raises(Exception, match="(?i)type"):  # a float64 file wants float64 inputs
        sess.run(None, {"x": x.astype(np.float32), "leader_R": rot.astype(np.float32)})
    (got,) = sess.run(None, {"x": x, "leader_R": rot})
    np.testing.assert_allclose(got, pred.predict(x, rot), atol=1e-10)


def test_onnx_export_needs_no_torch(tmp_path):
    pytest.importorskip("onnx")
    path = _random_trained("so2").save(tmp_path / "m")
    code = (
        "import sys\n"
        "from aerodock.deploy.export import export_onnx\n"
        f"export_onnx({str(path)!r}, {str(tmp_path / 'm.onnx')!r})\n"
        "assert 'torch' not in sys.modules, 'torch was imported'\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "m.onnx").stat().st_size > 1000
