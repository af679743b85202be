"""Per-trial random streams for batch-first simulation.

``TrialRNG(seed, n, first_trial)`` behaves like a ``numpy.random.Generator`` for draws whose
leading dimension is the batch size ``n``, but each trial ``i`` draws from its own stream, seeded
by ``(seed, first_trial + i)``. So a batch of N trials gives exactly the same numbers as N single
trials with the same seed and trial indices, while draws stay vectorised: each trial's stream is
pre-drawn in chunks (one short Python loop over trials per chunk, not per step).
"""

from __future__ import annotations

from typing import Any

import numpy as np

_CHUNK = 4096


class TrialRNG:
    """Batch random source with one independent stream per trial.

    Args:
        seed: campaign seed.
        n: number of trials in this batch.
        first_trial: index of the first trial (a single trial ``i`` is ``TrialRNG(seed, 1, i)``).
        trials: explicit trial indices, one per row, instead of ``first_trial + i`` (e.g. the
            same trials flown by several policies: common random numbers).
    """

    def __init__(self, seed: int, n: int, first_trial: int = 0, trials: Any = None):
        self.seed = int(seed)
        self.n = int(n)
        self.first_trial = int(first_trial)
        index = self.first_trial + np.arange(n) if trials is None else np.asarray(trials)
        if index.shape != (self.n,):
            raise ValueError(f"trials must hold {self.n} indices, got shape {index.shape}")
        self._gens = [np.random.default_rng([self.seed, int(t)]) for t in index]
        self._shared = np.random.default_rng([self.seed, -1 & 0x7FFFFFFF])
        self._buf = {"normal": np.empty((n, 0)), "uniform": np.empty((n, 0))}
        self._pos = {"normal": 0, "uniform": 0}

    def _take(self, kind: str, per_trial: int) -> np.ndarray:
        buf, pos = self._buf[kind], self._pos[kind]
        if pos + per_trial > buf.shape[1]:
            size = max(_CHUNK, per_trial)
            draw = (lambda g: g.standard_normal(size)) if kind == "normal" else (
                lambda g: g.random(size))
            fresh = np.stack([draw(g) for g in self._gens]) if self.n else np.empty((0, size))
            buf = np.concatenate([buf[:, pos:], fresh], axis=1)
            pos = 0
        self._buf[kind], self._pos[kind] = buf, pos + per_trial
        return buf[:, pos:pos + per_trial]

    def _batch(self, kind: str, size: Any) -> np.ndarray:
        shape = (size,) if isinstance(size, int | np.integer) else tuple(size or ())
        if not shape or shape[0] != self.n:
            # Not a per-trial draw: use a shared stream (still deterministic for a given seed).
            return (self._shared.standard_normal(shape) if kind == "normal"
                    else self._shared.random(shape))
        per_trial = int(np.prod(shape[1:], dtype=int))
        return self._take(kind, per_trial).reshape(shape)

    def standard_normal(self, size: Any = None) -> np.ndarray:
        """Standard normal draws; ``size[0] == n`` gives one row per trial."""
        return self._batch("normal", size)

    def normal(self, loc: Any = 0.0, scale: Any = 1.0, size: Any = None) -> np.ndarray:
        """Normal draws (per-trial when ``size[0] == n``)."""
        return loc + scale * self._batch("normal", size)

    def random(self, size: Any = None) -> np.ndarray:
        """Uniform draws in [0, 1) (per-trial when ``size[0] == n``)."""
        return self._batch("uniform", size)

    def uniform(self, low: Any = 0.0, high: Any = 1.0, size: Any = None) -> np.ndarray:
        """Uniform draws in [low, high) (per-trial when ``size[0] == n``)."""
        return low + (high - low) * self._batch("uniform", size)
