"""What the sample-efficiency studies learn from: reproduce's step 1 and the real-data split."""

from __future__ import annotations

import dataclasses
import re

import numpy as np

from aerodock.experiments.real_data import real_split
from aerodock.experiments.reproduce import SMOKE, learning_data
from aerodock.learning.datafiles import load_dataset
from aerodock.learning.runtime import Predictor


def test_learning_data_holds_out_its_test_flights_and_pools_model_flights(short_cfg, tmp_path):
    cfg = short_cfg  # bookkeeping, whatever the settled start's length (tests/short_mission.py)
    size = dataclasses.replace(
        SMOKE, test_flights_per_stage=1, se_pool_flights=5,
        curriculum={"flights_per_stage": 2, "stage0_depth_m": [0.9, 1.2], "min_depth_m": 0.9,
                    "deep_depths_m": [0.6], "deep_flights_per_stage": 2})
    said: list[str] = []
    got = learning_data(cfg, size, tmp_path, seed=0, say=said.append,
                        train_kwargs={"max_epochs": 5})
    assert [s["stage"] for s in got.curriculum["stages"]] == [0, 1]  # paper's, then deep
    assert said  # the curriculum's progress goes to say
    # one held-out flight per stage, saved, flown without a model and not trained on
    test_names = got.test_ds.flight_names
    assert sorted(n.split("-")[0] for n in test_names) == ["test0", "test1"]
    assert load_dataset(tmp_path / "heldout.npz").n == got.test_ds.n
    train_names = [lg.name for lg in got.train_logs]
    assert not set(test_names) & set(train_names)
    # the curriculum's 2 + 2 flights, then 5 // 5 pool flight per stage with the paper's model
    assert [n.split("-")[0] for n in train_names] == ["stage0"] * 2 + ["stage1"] * 2 + [
        "pool0", "pool1"]
    assert all(lg.meta["compensation"] == "observer+model" for lg in got.train_logs[4:])
    x = np.zeros((1, 9)) + [0, 0, 0.8, 0, 0, 0, 0, 0, 0]
    paper = Predictor.load(tmp_path / "models" / "paper")
    assert np.array_equal(got.predictor.predict(x, np.eye(3)[None]),
                          paper.predict(x, np.eye(3)[None]))
    final = Predictor.load(tmp_path / "models" / "final")
    assert np.array_equal(got.deep_predictor.predict(x, np.eye(3)[None]),
                          final.predict(x, np.eye(3)[None]))


def test_real_split_trains_on_flights_00_04_and_judges_05_06(shared_data):
    train_logs, test_logs, train_ds, test_ds = real_split(shared_data("neural-swarm", "swap_ss"))
    def numbers(logs):
        return sorted(re.search(r"_(\d\d)_cf\d+$", lg.name).group(1) for lg in logs)

    assert numbers(train_logs) == ["00", "00", "01", "01", "02", "02", "03", "03", "04", "04"]
    assert numbers(test_logs) == ["05", "05", "06", "06"]
    assert train_ds.n_flights == 10 and test_ds.n_flights == 4
    assert not set(train_ds.flight_names) & set(test_ds.flight_names)
    assert 3.0 < train_ds.minutes < 6.0  # the full curve's 3 minutes exist to draw from
