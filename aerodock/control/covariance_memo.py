"""A batch filter's shared covariance steps, each computed once per distinct covariance.

Freyja's filters (:mod:`aerodock.control.freyja_state_filter`,
:mod:`aerodock.control.freyja_estimator`) keep one 3x3 covariance for the whole batch (every trial
and axis runs the same timing), and each step of it (a propagation; a measurement update with its
gain) is a function of that covariance and the filter's constant matrices alone. The leader's and
the follower's filters run the same sequence of covariances, and every campaign of a process runs
it again from the same start, so :class:`CovarianceMemo` keeps each step's result by the
covariance's bytes and hands it back when the same covariance comes again: the same operations
ran once on the same numbers, so every filter gets the same numbers without the small matrix
products (and the 2x2 inverse) each control period.

The results are stored read-only: a filter replaces its covariance, it never writes into it.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

_MEMO: dict[tuple[str, bytes, bytes], Any] = {}
_MAX_ENTRIES = 50_000  # a campaign's covariances until they settle are a few thousand


class CovarianceMemo:
    """The memo of one filter model's covariance steps (shared by every filter of that model).

    Args:
        name: the filter's name (steps of different filters never share an entry).
        constants: the model's constant matrices and numbers the steps read.
    """

    def __init__(self, name: str, *constants: Any) -> None:
        self._name = name
        self._model = b"".join(np.asarray(c, dtype=float).tobytes() for c in constants)

    def step(self, kind: str, cov: np.ndarray,
             compute: Callable[[np.ndarray], tuple[np.ndarray, ...]]) -> tuple[np.ndarray, ...]:
        """``compute(cov)``'s arrays (read-only), computed the first time this step meets this
        covariance."""
        key = (f"{self._name}/{kind}", self._model, cov.tobytes())
        hit = _MEMO.get(key)
        if hit is None:
            hit = tuple(compute(cov))
            for arr in hit:
                arr.setflags(write=False)
            if len(_MEMO) >= _MAX_ENTRIES:
                _MEMO.clear()
            _MEMO[key] = hit
        return hit
