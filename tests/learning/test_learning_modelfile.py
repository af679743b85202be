"""Model files checked whole: model.json's own checksum, plausible normalisation, version 1 files,
leftover temporary directories, and the ONNX export's label bases and enforced tolerance."""

from __future__ import annotations

import copy
import io
import json
import os
import subprocess
import sys
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import numpy as np
import pytest
from test_learning_runtime import _inputs, _random_trained

from aerodock.learning.modelfile import (
    CHECKSUM_KEY,
    MODEL_VERSION,
    ModelFileError,
    ModelSpec,
    load_model_dir,
    model_checksum,
    save_model_dir,
    upgrade_model_dir,
)
from aerodock.learning.runtime import Predictor

X, ROT = _inputs(64, seed=3)
KINDS = ("so2", "so2-ext", "mlp", "zero")


def _save(kind: str, path: Path) -> Path:
    trained = _random_trained(kind)
    trained.info["data"] = {"label_bases": ["command"], "n_samples": 1000,
                            "vehicles": {"leader": {"mass_kg": 0.7}, "follower": {"mass_kg": 0.7}}}
    return trained.save(path)


def _doc(path: Path) -> dict:
    return json.loads((path / "model.json").read_text())


def _write(path: Path, doc: dict, reseal: bool = False) -> None:
    if reseal:
        doc = {k: v for k, v in doc.items() if k != CHECKSUM_KEY}
        doc[CHECKSUM_KEY] = model_checksum(doc)
    (path / "model.json").write_text(json.dumps(doc, indent=2))


def _leaves(doc, prefix=()):
    """Every path in a JSON document (containers too: a list or a dict is a field as well)."""
    if prefix:
        yield prefix
    if isinstance(doc, dict):
        for key, value in doc.items():
            yield from _leaves(value, (*prefix, key))
    elif isinstance(doc, list):
        for i, value in enumerate(doc):
            yield from _leaves(value, (*prefix, i))


def _get(doc, path):
    for key in path:
        doc = doc[key]
    return doc


def _variants(path, value):
    """Changed values of one field: numbers, strings, booleans, nulls, lists, dicts."""
    if path == ("kind",):
        return [k for k in KINDS if k != value]
    if path == ("activation",):
        return ["silu" if value == "tanh" else "tanh"]
    if isinstance(value, bool):
        return [not value]
    if isinstance(value, int):
        return [value + 1, -value - 1, float(value)]
    if isinstance(value, float):
        return [-value if value else 1.0, value + max(1e-3, 1e-3 * abs(value)), 0.0,
                int(value) if float(int(value)) != value else value + 0.5]
    if isinstance(value, str):
        return [value + "x", ""]
    if value is None:
        return [0, "x"]
    if isinstance(value, list):
        return [value[:-1], [*value, value[-1] if value else 0]]
    if isinstance(value, dict):
        return [{k: v for k, v in list(value.items())[:-1]}] if value else [{"x": 1}]
    raise AssertionError(f"unexpected value at {path}: {value!r}")


def _changed(doc, path, value):
    new = copy.deepcopy(doc)
    _get(new, path[:-1])[path[-1]] = value
    return new


def _prediction(path: Path) -> np.ndarray | None:
    try:
        return Predictor.load(path).predict(X, ROT)
    except ModelFileError:
        return None


@pytest.mark.parametrize("kind", ["so2", "mlp", "zero"])
def test_every_change_to_model_json_is_refused(tmp_path, kind):
    """Each field in turn (numbers, strings, lists, dicts; and deleted): the file as changed is
    refused with one line naming it. Re-sealed with a fresh checksum, the same change shows
    which fields alter a prediction: those the checksum alone stands guard over."""
    path = _save(kind, tmp_path / "m")
    doc = _doc(path)
    want = Predictor.load(path).predict(X, ROT)
    cases = [(p, v) for p in _leaves(doc) if p != (CHECKSUM_KEY,)
             for v in _variants(p, _get(doc, p))]
    cases += [(p, "delete") for p in _leaves(doc) if isinstance(_get(doc, p[:-1]), dict)]
    assert len(cases) > 40
    alters = set()
    for field_path, value in cases:
        if value == "delete":
            new = copy.deepcopy(doc)
            del _get(new, field_path[:-1])[field_path[-1]]
        else:
            new = _changed(doc, field_path, value)
        if new == doc:
            continue
        _write(path, new)
        with pytest.raises(ModelFileError) as err:
            Predictor.load(path)
        msg = str(err.value)
        assert "\n" not in msg and str(path) in msg, (field_path, msg)
        _write(path, new, reseal=True)
        got = _prediction(path)
        if got is not None and not np.array_equal(got, want):
            alters.add(field_path[:2])
    _write(path, doc)
    np.testing.assert_array_equal(Predictor.load(path).predict(X, ROT), want)
    if kind != "zero":  # what would slip through were model.json not under the checksum
        assert {("normalisation", "out_mean"), ("normalisation", "out_std"),
                ("normalisation", "in_mean"), ("normalisation", "in_std"),
                ("activation",)} <= alters, alters
    if kind != "mlp":
        assert kind == "zero" or ("features", "eps_pos_m") in alters


def test_the_audits_tampering_is_refused(tmp_path):
    path = _save("so2", tmp_path / "m")
    doc = _doc(path)
    flipped = copy.deepcopy(doc)
    flipped["normalisation"]["out_mean"][1] *= -1
    _write(path, flipped)
    with pytest.raises(ModelFileError, match="does not match its model_sha256"):
        Predictor.load(path)
    _write(path, {**doc, "kind": "zero"})
    with pytest.raises(ModelFileError, match="model_sha256"):
        Predictor.load(path)
    # a zero kind re-sealed, or in a version 1 file (no checksum): refused for its weights
    _write(path, {**doc, "kind": "zero"}, reseal=True)
    with pytest.raises(ModelFileError, match="kind 'zero' with layer sizes"):
        Predictor.load(path)
    huge = copy.deepcopy(doc)
    huge["normalisation"]["out_std"][0] = 1e300
    _write(path, huge, reseal=True)  # a fresh checksum does not make it plausible
    with pytest.raises(ModelFileError, match=r"out_std\[0\] = 1e\+300: beyond the plausible"):
        Predictor.load(path)


@pytest.mark.parametrize(("key", "index", "value", "match"), [
    ("out_std", 0, 1e300, "beyond the plausible 1000"),
    ("out_std", 1, 0.0, "at least 1e-06"),
    ("out_std", 1, -2.0, "at least 1e-06"),
    ("in_std", 2, 1e-9, "at least 1e-06"),
    ("in_mean", 0, 2e4, "beyond the plausible 10000"),
    ("out_mean", 1, -5e3, "beyond the plausible 1000"),
])
def test_implausible_normalisation_is_refused_on_save_and_load(tmp_path, key, index, value,
                                                                match):
    path = _save("so2", tmp_path / "m")
    spec, weights, doc = load_model_dir(path)
    values = np.array(getattr(spec, key))
    values[index] = value
    bad = ModelSpec(**{**spec.__dict__, key: values})
    with pytest.raises(ValueError, match=match):
        save_model_dir(tmp_path / "new", bad, weights)
    assert not (tmp_path / "new").exists()
    edited = copy.deepcopy(doc)
    edited["normalisation"][key][index] = value
    _write(path, edited, reseal=True)
    with pytest.raises(ModelFileError, match=match):
        Predictor.load(path)


def test_layout_is_not_a_change(tmp_path):
    path = _save("so2-ext", tmp_path / "m")
    want = Predictor.load(path).predict(X, ROT)
    doc = _doc(path)
    reordered = dict(reversed(list(doc.items())))
    (path / "model.json").write_text(json.dumps(reordered, separators=(",", ":")))
    np.testing.assert_array_equal(Predictor.load(path).predict(X, ROT), want)


@pytest.mark.parametrize("kind", KINDS)
def test_version_1_files_still_load_and_upgrade(tmp_path, kind):
    """A file written before model.json had a checksum loads as before (weights verified);
    re-saved it is version 2 with the same predictions."""
    path = _save(kind, tmp_path / "m")
    want = Predictor.load(path).predict(X, ROT)
    doc = _doc(path)
    assert doc["version"] == MODEL_VERSION == 2 and len(doc[CHECKSUM_KEY]) == 64
    v1 = {k: v for k, v in doc.items() if k != CHECKSUM_KEY}
    v1["version"] = 1
    _write(path, v1)
    np.testing.assert_array_equal(Predictor.load(path).predict(X, ROT), want)
    _write(path, {**v1, CHECKSUM_KEY: doc[CHECKSUM_KEY]})  # only the version edited
    with pytest.raises(ModelFileError, match="format version 1 with model_sha256"):
        Predictor.load(path)
    _write(path, {**doc, "version": True})
    with pytest.raises(ModelFileError, match="bad version"):
        Predictor.load(path)
    _write(path, v1)
    upgrade_model_dir(path)
    again = _doc(path)
    assert again["version"] == 2 and again[CHECKSUM_KEY] == model_checksum(again)
    assert again["training"] == doc["training"] and again["vehicles"] == doc["vehicles"]
    np.testing.assert_array_equal(Predictor.load(path).predict(X, ROT), want)


def test_version_1_zero_kind_with_weights_is_refused(tmp_path):
    path = _save("so2", tmp_path / "m")
    v1 = {k: v for k, v in _doc(path).items() if k != CHECKSUM_KEY}
    _write(path, {**v1, "version": 1, "kind": "zero"})
    with pytest.raises(ModelFileError, match="kind 'zero' with layer sizes or weights"):
        Predictor.load(path)


def _cli(*args) -> tuple[int, str, str]:
    from aerodock.cli import run

    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        rc = run([str(a) for a in args])
    return rc, out.getvalue(), err.getvalue()


def _one_error_line(err: str) -> str:
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    assert "Traceback" not in err
    return lines[0]


def test_commands_refuse_a_tampered_model(tmp_path, monkeypatch):
    monkeypatch.delenv("AERODOCK_DEBUG", raising=False)
    path = _save("so2", tmp_path / "m")
    probe = ("field", "probe", "--model", path, "--separation", "0.36", "--radial", "0",
             "--json")
    rc, out, _ = _cli(*probe)
    assert rc == 0 and json.loads(out)
    doc = _doc(path)
    flipped = copy.deepcopy(doc)
    flipped["normalisation"]["out_mean"][1] *= -1
    huge = copy.deepcopy(doc)
    huge["normalisation"]["out_std"][1] = 1e300
    for bad, reseal in ((flipped, False), (huge, True), ({**doc, "kind": "zero"}, False)):
        _write(path, bad, reseal=reseal)
        for args in (probe, ("dock", "--trials", "1", "--compensation", "model", "--model", path),
                     ("node", "--model", path, "--duration", "0.1"),
                     ("export", "--model", path, "--out", tmp_path / "m.onnx")):
            rc, out, err = _cli(*args)
            assert rc == 2, (args, err)
            assert "model.json" in _one_error_line(err)
    assert not (tmp_path / "m.onnx").exists()


def test_a_leftover_temp_dir_is_removed_by_the_next_save(tmp_path):
    """A kill inside the directory swap leaves `.NAME.PID.XXXXXXXX.tmp`; the next model saved
    in the same folder removes it (and nothing else)."""
    _save("so2", tmp_path / "a")
    code = ("import os, signal, sys\n"
            f"sys.path.insert(0, {str(Path(__file__).parent)!r})\n"
            "import aerodock.fileio.writes as f\n"
            "from test_learning_runtime import _random_trained\n"
            "real = f._fsync_dir\n"
            "def die(path):\n"
            "    if path.name.endswith('.tmp'): os.kill(os.getpid(), signal.SIGKILL)\n"
            "    real(path)\n"
            "f._fsync_dir = die\n"
            f"_random_trained('mlp').save({str(tmp_path / 'a')!r})\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert proc.returncode == -9, proc.stderr
    (tmp_path / "notes.tmp").mkdir()  # not ours
    left = sorted(p.name for p in tmp_path.iterdir())
    assert len(left) == 3 and any(n.startswith(".a.") and n.endswith(".tmp") for n in left)
    assert Predictor.load(tmp_path / "a").kind == "so2"  # the old model, whole
    _save("mlp", tmp_path / "b")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a", "b", "notes.tmp"]
    assert os.listdir(tmp_path / "a") and Predictor.load(tmp_path / "a").kind == "so2"


# -- ONNX: the label bases in the metadata, the tolerance enforced before the rename ----------

def test_onnx_metadata_carries_the_label_bases_and_checksum(tmp_path):
    pytest.importorskip("onnxruntime")
    from aerodock.deploy.export import export_onnx, read_onnx_metadata

    path = _save("so2", tmp_path / "m")
    meta = read_onnx_metadata(export_onnx(path, tmp_path / "m.onnx"))
    assert json.loads(meta["aerodock.label_bases"]) == ["command"]
    assert meta["aerodock.model_sha256"] == _doc(path)[CHECKSUM_KEY]
    bare = _random_trained("so2-ext").save(tmp_path / "bare")  # records no label bases
    assert json.loads(read_onnx_metadata(export_onnx(bare, tmp_path / "b.onnx"))
                      ["aerodock.label_bases"]) is None
    trained = _random_trained("mlp")  # a trained model, exported without a model directory
    trained.info["data"] = {"label_bases": ["thrust"]}
    meta = read_onnx_metadata(export_onnx(trained, tmp_path / "t.onnx"))
    assert json.loads(meta["aerodock.label_bases"]) == ["thrust"]


def _off_by(monkeypatch, delta: float) -> None:
    """The NumPy runtime, the export's reference, made to disagree with the graph."""
    real = Predictor.predict_wrench

    def shifted(self, x, leader_R):
        force, torque = real(self, x, leader_R)
        return force + delta, torque

    monkeypatch.setattr(Predictor, "predict_wrench", shifted)


@pytest.mark.parametrize("dtype", ["float32", "float64"])
def test_export_enforces_its_tolerance_and_leaves_no_file(tmp_path, monkeypatch, dtype):
    pytest.importorskip("onnxruntime")
    from aerodock.deploy.export import TOLERANCE, ExportCheckError, export_checked

    path = _save("so2", tmp_path / "m")
    out = tmp_path / "out" / "m.onnx"
    _, diffs = export_checked(path, out, dtype=dtype)
    assert diffs is not None and diffs["f_ext_mps2"] <= TOLERANCE[dtype]
    good = out.read_bytes()
    _off_by(monkeypatch, 1e-3)
    with pytest.raises(ExportCheckError, match=rf"tolerance .* {dtype}\); nothing written"):
        export_checked(path, out, dtype=dtype)
    assert out.read_bytes() == good and os.listdir(out.parent) == ["m.onnx"]
    out.unlink()
    with pytest.raises(ExportCheckError):
        export_checked(path, out, dtype=dtype)
    assert os.listdir(out.parent) == []
    monkeypatch.delenv("AERODOCK_DEBUG", raising=False)
    rc, _, err = _cli("export", "--model", path, "--out", out, "--dtype", dtype)
    assert rc == 2 and "failed its check" in _one_error_line(err)
    assert os.listdir(out.parent) == []
    _off_by(monkeypatch, -1e-3)  # the two shifts cancel: within tolerance again
    rc, out_text, err = _cli("export", "--model", path, "--out", out, "--dtype", dtype,
                             "--json")
    assert rc == 0, err
    assert json.loads(out_text)["max_abs_diff_vs_numpy_mps2"] <= TOLERANCE[dtype]


def test_a_kill_during_the_export_check_leaves_the_old_file(tmp_path):
    pytest.importorskip("onnxruntime")
    from aerodock.deploy.export import export_onnx

    old_model = _save("so2", tmp_path / "old")
    new_model = _save("mlp", tmp_path / "new")
    out = export_onnx(old_model, tmp_path / "m.onnx")
    before = out.read_bytes()
    code = ("import os, signal\n"
            "import aerodock.deploy.export as e\n"
            "def die(*args): os.kill(os.getpid(), signal.SIGKILL)\n"
            "e._check_file = die\n"
            f"e.export_onnx({str(new_model)!r}, {str(out)!r})\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert proc.returncode == -9, proc.stderr
    assert out.read_bytes() == before  # never the new, unchecked file
    temps = [p for p in tmp_path.iterdir() if p.name.startswith(".m.onnx.")]
    assert len(temps) == 1 and temps[0].stat().st_size > 0
    export_onnx(new_model, out)  # the next write checks, renames, and removes the leftover
    assert not temps[0].exists() and out.read_bytes() != before
