"""Every model kind learns a known field from flights like the shared swap flights.

The flights (``learning_synth.make_pass_log``) pass back and forth under a hovering leader, each
along its own heading: three flights, headings 0, 60 and 120 degrees, so every pass direction is
in exactly one flight, as the north-south passes are in one of the shared swap_ss flights. The
held-out flights pass along the same three headings (new random draws). The labels carry the
known field of ``learning_synth.true_field`` (an axisymmetric Gaussian jet with an outward
planar part) plus noise; the test compares each kind's held-out prediction with that field.

Stated accuracies (held-out RMSE against the true field, as a fraction of the true field's RMS;
measured on this data with the budget below: so2 kinds 0.02-0.03, mlp 0.22-0.28):

* ``so2``, ``so2-ext``, ``so2-wrench``: below 0.1; ``so2-wrench``'s torque against the true
  wake torque below 0.2 of that torque's RMS (measured 0.05);
* ``mlp``: below 0.4. It works in world coordinates, so it must learn the jet separately along
  each pass direction it has seen.

With a flight split (the rule of ``train_model`` before ``split="auto"``) one of the three flights
is held out for validation: the MLP never trains on one pass direction, its validation loss
rises from the first epochs, early stopping keeps an almost untrained network and it fails the
0.4 (measured 0.58-0.67, best epoch 1-2), as it did on the swap_ss flights; the so2 kinds lose a
third of their data there too (0.04-0.09).
"""

from __future__ import annotations

import numpy as np
import pytest
from learning_synth import make_pass_logs

from aerodock.learning.dataset import build_dataset
from aerodock.learning.evaluate import evaluate
from aerodock.learning.train import train_model

HEADINGS_RAD = np.deg2rad([0.0, 60.0, 120.0])
FIELD_FRACTION = {"so2": 0.1, "so2-ext": 0.1, "so2-wrench": 0.1, "mlp": 0.4}
"""Largest held-out RMSE against the true field, as a fraction of its RMS, per kind."""
TORQUE_FRACTION = 0.2
"""Largest held-out torque RMSE against the true wake torque, as a fraction of its RMS."""
BUDGET = {"max_epochs": 150, "patience": 20}
"""The same training budget for every kind (about 2-5 s of CPU each)."""


@pytest.fixture(scope="module")
def pass_train():
    """Three 25 s flights, one per heading (7 500 samples)."""
    return build_dataset(make_pass_logs(np.random.default_rng(3), HEADINGS_RAD, duration_s=25.0))


@pytest.fixture(scope="module")
def pass_test():
    """Three 15 s held-out flights along the same headings."""
    return build_dataset(make_pass_logs(np.random.default_rng(11), HEADINGS_RAD))


@pytest.mark.parametrize("kind", ["so2", "so2-ext", "so2-wrench", "mlp"])
def test_each_kind_learns_a_known_field(kind, pass_train, pass_test):
    trained = train_model(kind, pass_train, seed=0, **BUDGET)
    assert trained.info["split"] == "time-blocks"  # 3 flights: fewer than a flight split needs
    ev = evaluate(trained.predictor(), pass_test)
    truth_rms = float(np.sqrt(np.mean(pass_test.y_true_mean ** 2)))
    err = ev["all"]["model_vs_true_mean"]["rmse_mps2"]["overall"]
    assert err < FIELD_FRACTION[kind] * truth_rms, (
        f"{kind}: held-out RMSE {err:.3f} m/s^2 against the true field, its RMS {truth_rms:.3f}; "
        f"best epoch {trained.info['best_epoch']} of {trained.info['epochs']}")
    # It learnt: far better than the zero model on the labels too.
    assert ev["all"]["model"]["rmse_mps2"]["overall"] < 0.5 * ev["all"]["zero"]["rmse_mps2"][
        "overall"]
    if kind == "so2-wrench":
        torque = ev["torque"]["all"]
        assert torque["model_vs_true"]["rmse_nm"]["overall"] < (
            TORQUE_FRACTION * torque["true_rms_nm"])
    # The learning curves: one training and one validation loss per epoch.
    curve = trained.info["history"]
    assert len(curve["train_loss"]) == len(curve["val_loss"]) == trained.info["epochs"]
    assert min(curve["val_loss"]) == pytest.approx(trained.info["val_loss"], rel=1e-3)
