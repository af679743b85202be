"""``model.json``'s training record is the dict ``train_model`` wrote before the typed records.

The expected objects are built by the statements ``train_model`` ran before
:class:`~aerodock.learning.records.TrainingRecord` existed, from the same fabricated values, and
compared as JSON text (keys, order, values).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from learning_synth import make_logs

from aerodock.learning.dataset import build_dataset
from aerodock.learning.records import (
    FitRecord,
    Hyperparameters,
    TrainingOutcome,
    TrainingRecord,
)
from aerodock.learning.train import train_model


def _text(obj: object) -> str:
    return json.dumps(obj, indent=2)


def _fit(wrench: bool, validation: bool, truth: bool) -> dict:
    """_fit_record's dicts of both parts, as train_model merged them before the records."""
    fit: dict = {"train_rmse_mps2": 0.5}
    if wrench:
        fit["train_rmse_torque_nm"] = 0.01
        if truth:
            fit["train_torque_vs_true_rmse_nm"] = 0.002
            fit["train_true_torque_rms_nm"] = 0.003
    if validation:
        fit["val_rmse_mps2"] = 0.6
        if wrench:
            fit["val_rmse_torque_nm"] = 0.02
            if truth:
                fit["val_torque_vs_true_rmse_nm"] = 0.004
                fit["val_true_torque_rms_nm"] = 0.005
    else:
        fit["val_rmse_mps2"] = None
    return fit


@pytest.mark.parametrize(("wrench", "validation", "truth"),
                         [(False, True, False), (False, False, False), (True, True, True),
                          (True, True, False), (True, False, True)])
def test_model_json_training_is_the_old_info(wrench, validation, truth):
    hyper = {"hidden": [32, 32], "activation": "tanh", "lr": 3e-3, "batch_size": 256,
             "weight_decay": 0.0, "max_epochs": 3, "patience": 20, "val_fraction": 0.2,
             "split_rule": "auto", "optimizer": "Adam", "loss": "MSE (m^2/s^4, world NED)"}
    wake = {"names": ["v_h"], "default": [1.0], "min": [0.9], "max": [1.1]} if wrench else None
    info: dict = {"kind": "so2", "seed": 0, "data": {"n_samples": 100}, "spectral_norm": False,
                  "hyperparameters": dict(hyper)}
    if wake is not None:
        info["wake_scales"] = wake
    fit = _fit(wrench, validation, truth)
    history = {"loss": "MSE", "train_loss": [1.0, 0.5], "val_loss": [1.1, 0.6]}
    outcome = {"split": "time-blocks", "n_train": 80, "n_val": 20, "val_flights": [],
               "epochs": 2, "best_epoch": 2, "stopped": "max_epochs", "train_loss": 0.25,
               "val_loss": 0.36 if validation else None}
    info.update({**outcome, **fit, "train_time_s": 1.5, "torch_version": "2.3",
                 "history": history})
    record = TrainingRecord(
        kind="so2", seed=0, data={"n_samples": 100}, spectral_norm=False,
        hyperparameters=Hyperparameters(**hyper), wake_scales=wake,
        outcome=TrainingOutcome(**outcome, fit=FitRecord.from_parts(fit)), train_time_s=1.5,
        torch_version="2.3", history=history)
    assert _text(record.to_json()) == _text(info)


def test_a_kind_with_nothing_to_train_records_its_settings_only():
    ds = build_dataset(make_logs(np.random.default_rng(5), n_flights=2, duration_s=3.0))
    trained = train_model("zero", ds, seed=2)
    assert list(trained.info) == ["kind", "seed", "data", "spectral_norm", "hyperparameters",
                                  "train_time_s"]
    assert trained.info == trained.record.to_json()
    assert trained.record.outcome is None and trained.info["seed"] == 2
