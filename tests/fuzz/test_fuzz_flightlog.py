"""FlightLog files damaged at random: every read ends in a FlightLogError or valid flights."""

from __future__ import annotations

import json
import random
import zipfile

import numpy as np
from fuzz_helpers import (
    assert_clean,
    count,
    mutate_bytes,
    n_cases,
    npy_bytes,
    npy_header_only,
    rewrite_npz,
    run_cli,
)

from aerodock.flightlog import FIELDS, FlightLog, FlightLogError, load_flightlogs

BAD_META = [
    "[]", "3", '"text"', "null", "{", "", "[" * 5000 + "]" * 5000, '{"a":' * 5000 + "1" +
    "}" * 5000, '{"name": 3}', '{"name": null, "source": []}', '{"label_basis": 5}',
    '{"leader_mass_kg": "x", "follower_mass_kg": -1}', '{"follower_mass_kg": NaN}',
    '{"flights": 3}', '{"flights": [1, "a", null]}', '{"flights": [{"dt_s": "x"}]}',
    '{"sources": 5, "warnings": 7, "labels": []}', '{"flights": [{"name": []}]}',
]


def _bad_arrays(shape: tuple[int, ...]) -> list[np.ndarray]:
    return [
        np.array([1, 2]), np.array("x"), np.array(1.5), np.zeros((0,)), np.full(shape, np.nan),
        np.full(shape, 1e300), np.zeros((3, 3, 3)), np.array(["a", "b"]), np.array(2**62),
        np.array(-1), np.ones(shape, dtype=bool), np.zeros(shape, dtype=np.int8),
        np.zeros(shape, dtype=np.complex128), np.zeros(shape[:1] + (4,)),
        np.zeros(shape, dtype=np.float16), np.zeros(shape[::-1]),
    ]


def _structural(base, path, rng: random.Random) -> None:
    """Replace one or two members of the base file with crafted arrays or headers."""
    with zipfile.ZipFile(base) as zf:
        names = zf.namelist()
    replace: dict[str, bytes] = {}
    drop: tuple[str, ...] = ()
    for _ in range(rng.randint(1, 2)):
        name = rng.choice(names)
        key = name[:-4]
        roll = rng.random()
        if key.endswith("meta") and roll < 0.7:
            replace[name] = npy_bytes(np.array(rng.choice(BAD_META)))
        elif roll < 0.15:
            drop = (name,)
        elif roll < 0.3:
            replace[name] = npy_header_only((10**13,))
        elif roll < 0.38:
            replace[name] = npy_header_only((2**40, 2**30))
        elif roll < 0.45:
            replace[name] = npy_header_only((5,), "|O")
        else:
            replace[name] = npy_bytes(rng.choice(_bad_arrays((300, 3))))
    rewrite_npz(base, path, replace, drop)


def _unsupported_compression(base, path) -> None:
    """Set the compression method of the first member to one zipfile does not know."""
    blob = bytearray(base.read_bytes())
    blob[8:10] = (99).to_bytes(2, "little")  # local file header: compression method
    central = blob.find(b"PK\x01\x02")
    blob[central + 10:central + 12] = (99).to_bytes(2, "little")  # and the central directory's
    path.write_bytes(bytes(blob))


def _check_load(path) -> str:
    try:
        logs = load_flightlogs(path)
    except FlightLogError as err:
        assert "\n" not in str(err)
        return "refused"
    assert all(isinstance(log, FlightLog) for log in logs)
    for log in logs:
        assert isinstance(log.meta, dict)
        for name in FIELDS:
            assert np.all(np.isfinite(getattr(log, name)))
    return "read"


def test_damaged_flightlogs_are_refused_cleanly(flightlog_file, tmp_path):
    rng = random.Random(20261123)
    base_bytes = flightlog_file.read_bytes()
    outcomes = {"read": 0, "refused": 0}
    for i in range(n_cases(400)):
        path = tmp_path / f"m{i % 50}.npz"
        if i % 3 == 0:
            path.write_bytes(mutate_bytes(base_bytes, rng))
        elif i == 1:
            _unsupported_compression(flightlog_file, path)
        else:
            _structural(flightlog_file, path, rng)
        outcomes[_check_load(path)] += 1
        count("flightlog-load")
    assert outcomes["refused"] > 0.5 * sum(outcomes.values())


def test_named_flightlog_defects(flightlog_file, tmp_path):
    """The defects issue 12 lists, one by one: each is a one-line FlightLogError."""
    cases = {
        "meta is a list": {"f0/meta.npy": npy_bytes(np.array("[]"))},
        "meta nested deeply": {"f0/meta.npy": npy_bytes(np.array("[" * 100000 + "]" * 100000))},
        "version an array": {"version.npy": npy_bytes(np.array([1, 1]))},
        "n_flights an array": {"n_flights.npy": npy_bytes(np.array([2, 2]))},
        "n_flights a string": {"n_flights.npy": npy_bytes(np.array("2"))},
        "1e13 floats declared": {"f0/t_s.npy": npy_header_only((10**13,))},
        "object array": {"f0/t_s.npy": npy_header_only((3,), "|O")},
        "zero quaternions": {"f0/leader_quat.npy": npy_bytes(np.zeros((300, 4)))},
    }
    for what, replace in cases.items():
        path = tmp_path / f"{what.replace(' ', '_')}.npz"
        rewrite_npz(flightlog_file, path, dict(replace))
        try:
            load_flightlogs(path)
        except FlightLogError as err:
            assert "\n" not in str(err), what
        else:
            raise AssertionError(f"{what}: read without error")
        count("flightlog-load")
    path = tmp_path / "compression.npz"
    _unsupported_compression(flightlog_file, path)
    try:
        load_flightlogs(path)
    except FlightLogError:
        pass
    else:
        raise AssertionError("unsupported compression read without error")


def test_damaged_flightlogs_through_the_cli(flightlog_file, model_dir, tmp_path):
    """``evaluate`` and ``train`` on damaged files: exit 0 or 2, one line, strict JSON."""
    rng = random.Random(7)
    base_bytes = flightlog_file.read_bytes()
    good_model = (model_dir / "model.json").read_text()
    results = []
    for i in range(n_cases(40)):
        path = tmp_path / f"c{i}.npz"
        if i % 2:
            path.write_bytes(mutate_bytes(base_bytes, rng))
        else:
            _structural(flightlog_file, path, rng)
        if i % 4 == 0:
            out = tmp_path / "trained"
            results.append(run_cli(["train", "--data", path, "--out", out, "--max-epochs", "1",
                                    "--json"], family="cli-train"))
        else:
            results.append(run_cli(["evaluate", "--model", model_dir, "--data", path, "--json"],
                                   family="cli-evaluate"))
    assert (model_dir / "model.json").read_text() == good_model
    assert_clean(results)
    json.loads(good_model)


def test_damaged_dataset_files(flightlog_file, model_dir, tmp_path):
    """Dataset files (``save_dataset``) damaged at random: a DataError or a valid dataset."""
    from aerodock.learning.datafiles import load_data_paths, save_dataset
    from aerodock.learning.dataset import DataError, build_dataset

    base = save_dataset(tmp_path / "base_ds.npz", build_dataset(load_flightlogs(flightlog_file)))
    blob = base.read_bytes()
    rng = random.Random(31)
    results = []
    for i in range(n_cases(100)):
        path = tmp_path / f"d{i % 20}.npz"
        if i % 2:
            path.write_bytes(mutate_bytes(blob, rng))
        else:
            _structural(base, path, rng)
        try:
            ds = load_data_paths([path])
        except DataError as err:
            assert "\n" not in str(err)
        else:
            assert np.all(np.isfinite(ds.x)) and np.all(np.isfinite(ds.y))
            if len(results) < n_cases(10):  # the loadable ones through the CLI as well
                args = (["evaluate", "--model", model_dir] if len(results) % 2 else
                        ["train", "--out", tmp_path / "t", "--max-epochs", "1"])
                results.append(run_cli([*args, "--data", path, "--json"], family="cli-dataset"))
        count("dataset-load")
    assert_clean(results)
