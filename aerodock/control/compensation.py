"""Feed-forward predictors of the external (downwash) acceleration, ``f_ext_hat``.

Anything with ``predict_bodies(leader: BodyState, follower: BodyState) -> (n, 3)`` (m/s², NED) can
be the follower's feed-forward: the learnt model (``aerodock.learning.runtime.Predictor``), the
zero predictor, or the oracle, which reads the simulator's true mean field (an upper bound only:
no real vehicle has it).
"""

from __future__ import annotations

from enum import StrEnum
from typing import Protocol

import numpy as np

from aerodock.downwash.base import BodyState


class Compensation(StrEnum):
    """What the follower subtracts from its desired acceleration before inversion."""

    NONE = "none"  # plain LQR
    OBSERVER = "observer"  # bias observer (the paper's LQG baseline, "without model")
    MODEL = "model"  # bias observer + learnt model feed-forward ("with model")
    ORACLE = "oracle"  # bias observer + the true mean field (upper bound)


class AccelPredictor(Protocol):
    """The interface of a feed-forward predictor."""

    def predict_bodies(self, leader: BodyState, follower: BodyState) -> np.ndarray:
        """(n, 3) predicted acceleration on the follower, m/s², NED."""


class ZeroPredictor:
    """Predicts no external force."""

    def predict_bodies(self, leader: BodyState, follower: BodyState) -> np.ndarray:
        """(n, 3) zeros."""
        return np.zeros_like(follower.p)


class OraclePredictor:
    """The simulator's true mean field (needs a field with ``mean_acceleration``)."""

    def __init__(self, field):
        if not hasattr(field, "mean_acceleration"):
            raise ValueError("the oracle needs a field with mean_acceleration(); this one has none")
        self.field = field

    def predict_bodies(self, leader: BodyState, follower: BodyState) -> np.ndarray:
        """(n, 3) the field's mean acceleration at the given states."""
        return self.field.mean_acceleration(leader, follower)
