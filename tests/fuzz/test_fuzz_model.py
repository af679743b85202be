"""Model directories damaged at random: a ModelFileError, or a predictor that gives finite numbers.

Covers model.json (values replaced, keys deleted, deep nesting, text damage, extreme feature
constants; half of the damaged documents re-sealed with a fresh ``model_sha256`` so that the
checks behind the checksum are reached), single-field tampering through the command line (refused
unless re-sealed), and weights.npz (byte damage, crafted members with both checksums updated so
that the npz parser itself is reached).
"""

from __future__ import annotations

import copy
import hashlib
import json
import random
import shutil

import numpy as np
from fuzz_helpers import (
    NASTY_VALUES,
    assert_clean,
    count,
    mutate_bytes,
    n_cases,
    npy_bytes,
    npy_header_only,
    rewrite_npz,
    run_cli,
)

from aerodock.learning.modelfile import CHECKSUM_KEY, ModelFileError, model_checksum
from aerodock.learning.runtime import Predictor

X = np.array([[0.05, -0.02, 0.4, 0.1, 0.0, 0.0, 0.0, 0.2, -0.1],
              [0.0, 0.0, 0.36, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]])
R = np.repeat(np.eye(3)[None], 2, 0)


def _paths(doc, prefix=()):
    """Every (path tuple) inside a JSON document."""
    yield prefix
    if isinstance(doc, dict):
        for k, v in doc.items():
            yield from _paths(v, (*prefix, k))
    elif isinstance(doc, list):
        for i, v in enumerate(doc):
            yield from _paths(v, (*prefix, i))


def _set(doc, path, value, delete=False):
    target = doc
    for key in path[:-1]:
        target = target[key]
    if delete and isinstance(target, dict):
        del target[path[-1]]
    else:
        target[path[-1]] = value


def _mutate_doc(doc, rng: random.Random):
    doc = copy.deepcopy(doc)
    paths = [p for p in _paths(doc) if p]
    for _ in range(rng.randint(1, 3)):
        path = rng.choice(paths)
        roll = rng.random()
        try:
            if roll < 0.15:
                _set(doc, path, None, delete=True)
            elif roll < 0.25:
                _set(doc, path, rng.choice([1e-300, 1e308, 0.0, -1e-3, 1e-9, 2.0]))
            else:
                _set(doc, path, rng.choice(NASTY_VALUES))
        except (KeyError, IndexError, TypeError):
            pass
        paths = [p for p in _paths(doc) if p]
    return doc


def _seal(doc):
    """The document with a fresh checksum of itself (what a deliberate edit would do)."""
    doc = {k: v for k, v in doc.items() if k != CHECKSUM_KEY}
    doc[CHECKSUM_KEY] = model_checksum(doc)
    return doc


def _check(model) -> str:
    try:
        predictor = Predictor.load(model)
    except ModelFileError as err:
        assert "\n" not in str(err)
        return "refused"
    predictor.predict(X, R)
    predictor.predict_one(X[1], R[1])
    return "loaded"


def _copy(model_dir, dst):
    if dst.exists():
        shutil.rmtree(dst)
    shutil.copytree(model_dir, dst)
    return dst


def test_damaged_model_json(model_dir, tmp_path):
    rng = random.Random(3)
    doc = json.loads((model_dir / "model.json").read_text())
    text = (model_dir / "model.json").read_text()
    outcomes = {"refused": 0, "loaded": 0}
    for i in range(n_cases(400)):
        model = _copy(model_dir, tmp_path / "m")
        if i % 4 == 0:
            (model / "model.json").write_bytes(mutate_bytes(text.encode(), rng))
        else:
            damaged = _mutate_doc(doc, rng)
            sealed = i % 2 == 1
            (model / "model.json").write_text(json.dumps(_seal(damaged) if sealed else damaged))
        outcome = _check(model)
        if i % 4 and not sealed and damaged != doc:
            assert outcome == "refused", "an edited model.json loaded"
        outcomes[outcome] += 1
        count("model-json")
    assert outcomes["refused"] > 0 and outcomes["loaded"] > 0


def test_named_model_defects(model_dir, tmp_path):
    """Deep nesting and extreme feature constants are one-line ModelFileErrors."""
    doc = json.loads((model_dir / "model.json").read_text())
    cases = {"nested": "[" * 100000 + "]" * 100000}
    for eps in (1e-300, 1e308, float("nan")):
        bad = copy.deepcopy(doc)
        bad["features"]["eps_pos_m"] = eps
        cases[f"eps {eps}"] = json.dumps(_seal(bad))
    for key, value in (("out_std", 1e300), ("in_std", 0.0), ("out_mean", -1e4)):
        bad = copy.deepcopy(doc)
        bad["normalisation"][key][0] = value
        cases[f"{key} {value}"] = json.dumps(_seal(bad))
    for what, text in cases.items():
        model = _copy(model_dir, tmp_path / "m")
        (model / "model.json").write_text(text)
        try:
            Predictor.load(model)
        except ModelFileError as err:
            assert "\n" not in str(err), what
        else:
            raise AssertionError(f"{what}: loaded")
        res = run_cli(["field", "probe", "--model", model, "--separation", "0.36", "--radial",
                       "0", "--json"], family="cli-model")
        assert_clean([res])
        assert res.rc == 2


def test_damaged_weights(model_dir, tmp_path):
    rng = random.Random(4)
    blob = (model_dir / "weights.npz").read_bytes()
    doc = json.loads((model_dir / "model.json").read_text())
    for i in range(n_cases(75)):
        model = _copy(model_dir, tmp_path / "m")
        weights = model / "weights.npz"
        if i % 2:
            weights.write_bytes(mutate_bytes(blob, rng))
        else:
            name = rng.choice(["W0.npy", "b0.npy", "W1.npy", "b2.npy"])
            member = rng.choice([npy_header_only((10**13,)), npy_header_only((3,), "|O"),
                                 npy_bytes(np.full((4, 4), np.nan)), npy_bytes(np.array("x")),
                                 npy_bytes(np.zeros((64, 6), dtype=np.float32) + 1e38)])
            rewrite_npz(model_dir / "weights.npz", weights, {name: member})
        if rng.random() < 0.7:  # keep the checksum consistent so the npz parser is reached
            fixed = copy.deepcopy(doc)
            fixed["weights"]["sha256"] = hashlib.sha256(weights.read_bytes()).hexdigest()
            (model / "model.json").write_text(json.dumps(_seal(fixed)))
        _check(model)
        count("model-weights")


def test_damaged_models_through_the_cli(model_dir, tmp_path):
    rng = random.Random(8)
    doc = json.loads((model_dir / "model.json").read_text())
    results = []
    for i in range(n_cases(75)):
        model = _copy(model_dir, tmp_path / f"m{i % 3}")
        (model / "model.json").write_text(json.dumps(_mutate_doc(doc, rng)))
        args = ["field", "probe", "--model", model, "--separation",
                rng.choice(["0.36", "0", "-0.5", "1e3", "nan"]), "--radial", "0.1", "--json"]
        if i % 10 == 0:
            args = ["export", "--model", model, "--out", tmp_path / "m.onnx", "--json"]
        results.append(run_cli(args, family="cli-model"))
    assert_clean(results)


def _fields(doc, prefix=()):
    """Every field of a document with a value that is not a container."""
    if isinstance(doc, dict):
        for k, v in doc.items():
            yield from _fields(v, (*prefix, k))
    elif isinstance(doc, list):
        if not doc:
            yield prefix
        for i, v in enumerate(doc):
            yield from _fields(v, (*prefix, i))
    elif prefix:
        yield prefix


def _tampered(value, rng: random.Random):
    """A plausible-looking edit of one value (what a hand edit or a bad merge does)."""
    if isinstance(value, bool):
        return not value
    if isinstance(value, int | float):
        return rng.choice([-value, value * 1.01 + 0.01, 0, 1e300, value + 1])
    if isinstance(value, str):
        return rng.choice(["zero", "so2", "so2-ext", "mlp", "silu", "tanh", "thrust",
                           "command", value.upper(), ""])
    return rng.choice([0, "x", [], None])


def test_tampered_model_json_through_the_cli(model_dir, tmp_path):
    """One field of model.json changed by hand: every command refuses it (exit 2, one
    error line, no traceback); re-sealed with a fresh checksum, exit 0 or 2, still clean."""
    rng = random.Random(11)
    doc = json.loads((model_dir / "model.json").read_text())
    fields = [p for p in _fields(doc) if p != (CHECKSUM_KEY,)]
    results = []
    for i in range(n_cases(60)):
        model = _copy(model_dir, tmp_path / f"t{i % 3}")
        path = rng.choice(fields)
        bad = copy.deepcopy(doc)
        _set(bad, path, _tampered(_get(bad, path), rng))
        sealed = i % 3 == 2
        (model / "model.json").write_text(json.dumps(_seal(bad) if sealed else bad, indent=1))
        args = ["field", "probe", "--model", model, "--separation", "0.36", "--radial", "0",
                "--json"]
        if i % 6 == 0:
            args = ["export", "--model", model, "--out", tmp_path / "t.onnx", "--json"]
        elif i % 6 == 3 and not sealed and bad != doc:  # refused before ROS is touched
            args = ["node", "--model", model, "--duration", "0.1"]
        res = run_cli(args, family="cli-model-tampered")
        results.append(res)
        if not sealed and bad != doc:
            assert res.rc == 2 and "model.json" in res.err, (path, res.err)
    assert_clean(results)


def _get(doc, path):
    for key in path:
        doc = doc[key]
    return doc
