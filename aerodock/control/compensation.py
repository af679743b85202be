"""Feed-forward predictors of the external (downwash) acceleration, ``f_ext_hat``.

Anything with ``predict_bodies(leader: BodyState, follower: BodyState) -> (n, 3)`` (m/s², NED) can
be the follower's feed-forward: the learnt model (``aerodock.learning.runtime.Predictor``), the
zero predictor, or the oracle, which reads the simulator's true mean field (an upper bound only:
no real vehicle has it; for a plug-in field without ``mean_acceleration`` the mean is estimated by
:func:`aerodock.downwash.mean.mean_acceleration_fn`).
"""

from __future__ import annotations

from enum import StrEnum
from typing import Protocol

import numpy as np

from aerodock.downwash.base import BodyState
from aerodock.downwash.mean import DEFAULT_DT_S, mean_acceleration_fn, mean_source


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
    """The simulator's true mean field: the field's ``mean_acceleration`` or, when it has none,
    an estimate on a private copy of the field (the simulated trials' turbulence is untouched).

    Args:
        field: the simulated world's downwash field.
        dt_s: the physics step, s (the step the estimate passes to ``acceleration``).
    """

    def __init__(self, field, dt_s: float = DEFAULT_DT_S):
        self.field = field
        self.mean_fn = mean_acceleration_fn(field, dt_s=dt_s)
        self.source = mean_source(self.mean_fn)

    def predict_bodies(self, leader: BodyState, follower: BodyState) -> np.ndarray:
        """(n, 3) the field's mean acceleration at the given states."""
        return self.mean_fn(leader, follower)
