"""Fixtures for the learning tests: synthetic FlightLogs (see ``learning_synth``).

The simulator is developed separately, so these tests build their own flights with a known,
SO(2)-equivariant downwash field (``learning_synth.true_field``).
"""

from __future__ import annotations

import numpy as np
import pytest
from learning_synth import make_logs

from aerodock.flightlog import FlightLog


@pytest.fixture(scope="session")
def synth_logs() -> list[FlightLog]:
    """Six 20 s synthetic flights (12 000 samples)."""
    return make_logs(np.random.default_rng(7), n_flights=6, duration_s=20.0)


@pytest.fixture(scope="session")
def synth_ds(synth_logs):
    """The synthetic flights as a Dataset."""
    from aerodock.learning.dataset import build_dataset

    return build_dataset(synth_logs)


@pytest.fixture(scope="session")
def trained_so2(synth_ds):
    """A quickly trained so2 model (shared by tests that need a trained model)."""
    from aerodock.learning.train import train_model

    return train_model("so2", synth_ds, seed=0, max_epochs=40, patience=10)
