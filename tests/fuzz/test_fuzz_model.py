"""Model directories damaged at random: a ModelFileError, or a predictor that gives finite numbers.

Covers model.json (values replaced, keys deleted, deep nesting, text damage, extreme feature
constants) and weights.npz (byte damage, crafted members with the checksum updated so that the
npz parser itself is reached).
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

from aerodock.learning.modelfile import ModelFileError
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
    for i in range(n_cases(800)):
        model = _copy(model_dir, tmp_path / "m")
        if i % 4 == 0:
            (model / "model.json").write_bytes(mutate_bytes(text.encode(), rng))
        else:
            (model / "model.json").write_text(json.dumps(_mutate_doc(doc, rng)))
        outcomes[_check(model)] += 1
        count("model-json")
    assert outcomes["refused"] > 0


def test_named_model_defects(model_dir, tmp_path):
    """Deep nesting and extreme feature constants are one-line ModelFileErrors."""
    doc = json.loads((model_dir / "model.json").read_text())
    cases = {"nested": "[" * 100000 + "]" * 100000}
    for eps in (1e-300, 1e308, float("nan")):
        bad = copy.deepcopy(doc)
        bad["features"]["eps_pos_m"] = eps
        cases[f"eps {eps}"] = json.dumps(bad)
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
    for i in range(n_cases(300)):
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
            (model / "model.json").write_text(json.dumps(fixed))
        _check(model)
        count("model-weights")


def test_damaged_models_through_the_cli(model_dir, tmp_path):
    rng = random.Random(8)
    doc = json.loads((model_dir / "model.json").read_text())
    results = []
    for i in range(n_cases(150)):
        model = _copy(model_dir, tmp_path / f"m{i % 3}")
        (model / "model.json").write_text(json.dumps(_mutate_doc(doc, rng)))
        args = ["field", "probe", "--model", model, "--separation",
                rng.choice(["0.36", "0", "-0.5", "1e3", "nan"]), "--radial", "0.1", "--json"]
        if i % 10 == 0:
            args = ["export", "--model", model, "--out", tmp_path / "m.onnx", "--json"]
        results.append(run_cli(args, family="cli-model"))
    assert_clean(results)
