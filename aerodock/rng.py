"""Per-trial random streams for batch-first simulation.

``TrialRNG(seed, n, first_trial)`` behaves like a ``numpy.random.Generator`` for draws whose
leading dimension is the batch size ``n``, but each trial ``i`` draws from its own stream, seeded
by ``(seed, first_trial + i)``. So a batch of N trials gives exactly the same numbers as N single
trials with the same seed and trial indices, while draws stay vectorised: each trial's stream is
pre-drawn in chunks (one short Python loop over trials per chunk, not per step).
"""

from __future__ import annotations

import copy
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import numpy as np

from aerodock.processes import usable_cores

# Draws per trial and refill. The normal and uniform buffers share each trial's generator,
# so the refill size fixes which of the stream's numbers each gets: changing it changes them.
_CHUNK = 4096
_BLOCK = 16  # trials drawn per scratch block at a refill


class TrialRNG:
    """Batch random source with one independent stream per trial.

    Args:
        seed: campaign seed.
        n: number of trials in this batch.
        first_trial: index of the first trial (a single trial ``i`` is ``TrialRNG(seed, 1, i)``).
        trials: explicit trial indices, one per row, instead of ``first_trial + i`` (e.g. the
            same trials flown by several policies: common random numbers).
        seeds: explicit campaign seeds, one per row, instead of ``seed`` for every row: several
            campaigns' trials flown as one batch, each row drawing the numbers it draws in its
            own campaign. Such a batch draws no shared numbers (they would be ``seed``'s only).
    """

    def __init__(self, seed: int, n: int, first_trial: int = 0, trials: Any = None,
                 seeds: Any = None):
        self.seed = int(seed)
        self.n = int(n)
        self.first_trial = int(first_trial)
        index = self.first_trial + np.arange(n) if trials is None else np.asarray(trials)
        if index.shape != (self.n,):
            raise ValueError(f"trials must hold {self.n} indices, got shape {index.shape}")
        row_seeds = (np.full(self.n, self.seed, dtype=np.int64) if seeds is None
                     else np.asarray(seeds, dtype=np.int64))
        if row_seeds.shape != (self.n,):
            raise ValueError(f"seeds must hold {self.n} seeds, got shape {row_seeds.shape}")
        self.seeds = row_seeds
        self._mixed = bool(np.any(row_seeds != self.seed))
        self._gens = [np.random.default_rng([int(s), int(t)]) for s, t in zip(row_seeds, index)]
        self._shared = np.random.default_rng([self.seed, -1 & 0x7FFFFFFF])
        # Pre-drawn numbers, draw-major (draws, n): row j holds every trial's j-th next draw, so
        # a block of draws is a contiguous (k, n) slice (fast to compute with, no copy).
        self._buf = {"normal": np.empty((0, n)), "uniform": np.empty((0, n))}
        self._pos = {"normal": 0, "uniform": 0}

    def take_rows(self, rows: np.ndarray) -> TrialRNG:
        """The streams of the trials at ``rows`` (indices into this batch), each where it stands
        now: a batch of ``len(rows)`` that draws the numbers these trials would draw next."""
        rows = np.asarray(rows, dtype=np.int64)
        out = copy.copy(self)
        out.n = int(rows.size)
        out.seeds = self.seeds[rows]
        out._gens = [copy.deepcopy(self._gens[i]) for i in rows]
        out._shared = copy.deepcopy(self._shared)
        out._buf = {kind: buf[:, rows] for kind, buf in self._buf.items()}
        out._pos = dict(self._pos)
        return out

    def _take(self, kind: str, per_trial: int) -> np.ndarray:
        """(per_trial, n): every trial's next ``per_trial`` draws, one row per draw (a view)."""
        self._reserve(kind, per_trial)
        pos = self._pos[kind]
        self._pos[kind] = end = pos + per_trial
        return self._buf[kind][pos:end]

    def _reserve(self, kind: str, per_trial: int) -> None:
        """The buffer holding every trial's next ``per_trial`` draws: when it does not, the
        unread rows kept and ``max(_CHUNK, per_trial)`` new ones drawn after them."""
        buf, pos = self._buf[kind], self._pos[kind]
        if pos + per_trial > buf.shape[0]:
            left = buf.shape[0] - pos
            size = max(_CHUNK, per_trial)
            new = np.empty((left + size, self.n))
            new[:left] = buf[pos:]
            _refill(self._gens, kind, size, new[left:])
            self._buf[kind], self._pos[kind] = new, 0

    def reserve_normals(self, per_trial: int) -> None:
        """Refill the normal buffer now if it does not hold every trial's next ``per_trial``
        draws, as the first draw past its end would (:meth:`normal_buffer`'s compiled reader
        calls it before a step whose draws overflow the buffer). The numbers drawn later are
        the same as long as nothing else draws from the trials' streams in between and
        ``per_trial`` stays below the refill's chunk (the size drawn is then the chunk either
        way)."""
        self._reserve("normal", int(per_trial))

    def _batch(self, kind: str, size: Any) -> np.ndarray:
        shape = (size,) if isinstance(size, int | np.integer) else tuple(size or ())
        if not shape or shape[0] != self.n:
            # Not a per-trial draw: use a shared stream (still deterministic for a given seed).
            if self._mixed:
                raise ValueError("a batch of several campaigns' trials cannot draw shared "
                                 "numbers: each campaign would draw its own")
            return (self._shared.standard_normal(shape) if kind == "normal"
                    else self._shared.random(shape))
        per_trial = 1
        for k in shape[1:]:
            per_trial *= int(k)
        block = self._take(kind, per_trial)
        if per_trial == 1:
            return block[0].reshape(shape)
        return np.ascontiguousarray(block.T).reshape(shape)

    def normal_buffer(self) -> tuple[np.ndarray, int]:
        """The pre-drawn standard normal numbers, draw-major (draws, n), and the cursor: the
        row of every trial's next draw. A compiled caller reads rows ``cursor..`` in the order
        :meth:`standard_normal_t` would hand them out, never past the buffer's end (before
        draws that would go past it, :meth:`reserve_normals` refills it as the Python path's
        draw would), then moves the cursor (:meth:`set_normal_cursor`)."""
        return self._buf["normal"], self._pos["normal"]

    def set_normal_cursor(self, cursor: int) -> None:
        """Mark the normal draws before row ``cursor`` of :meth:`normal_buffer` as used.

        Raises:
            ValueError: ``cursor`` is outside the buffer, or before the current cursor.
        """
        if not self._pos["normal"] <= cursor <= self._buf["normal"].shape[0]:
            raise ValueError(f"normal cursor {cursor} outside {self._pos['normal']}.."
                             f"{self._buf['normal'].shape[0]}")
        self._pos["normal"] = int(cursor)

    def standard_normal(self, size: Any = None) -> np.ndarray:
        """Standard normal draws; ``size[0] == n`` gives one row per trial."""
        return self._batch("normal", size)

    def standard_normal_t(self, k: int) -> np.ndarray:
        """(k, n) standard normal draws, draw-major: the numbers of ``standard_normal((n, k)).T``
        (a read-only-by-convention view; the hot loop's component-major form)."""
        return self._take("normal", k)

    def normal(self, loc: Any = 0.0, scale: Any = 1.0, size: Any = None) -> np.ndarray:
        """Normal draws (per-trial when ``size[0] == n``)."""
        return loc + scale * self._batch("normal", size)

    def random(self, size: Any = None) -> np.ndarray:
        """Uniform draws in [0, 1) (per-trial when ``size[0] == n``)."""
        return self._batch("uniform", size)

    def uniform(self, low: Any = 0.0, high: Any = 1.0, size: Any = None) -> np.ndarray:
        """Uniform draws in [low, high) (per-trial when ``size[0] == n``)."""
        return low + (high - low) * self._batch("uniform", size)


def _refill(gens: list[np.random.Generator], kind: str, size: int, out: np.ndarray) -> None:
    """Each trial's next ``size`` draws of ``kind`` into its column of ``out`` (size, n): drawn
    straight into a row of a small scratch block, then the block transposed into place (blocks
    of 16 trials stay in cache). From :data:`_THREADED_MIN` trials on, the trials are split
    between threads (NumPy draws and copies without the GIL): every stream is still drawn by
    one thread, in its own order, so the numbers are the same."""
    n = len(gens)
    threads = min(usable_cores(), n // _THREADED_MIN)
    if threads <= 1:
        _refill_columns(gens, kind, size, out, 0, n)
        return
    cuts = [(n * t // threads) // _BLOCK * _BLOCK for t in range(threads)] + [n]
    pool = _pool(threads)
    list(pool.map(lambda t: _refill_columns(gens, kind, size, out, cuts[t], cuts[t + 1]),
                  range(threads)))


def _refill_columns(gens: list[np.random.Generator], kind: str, size: int, out: np.ndarray,
                    start: int, stop: int) -> None:
    """:func:`_refill` for the trials ``start..stop``."""
    scratch = np.empty((min(_BLOCK, stop - start), size))
    for i in range(start, stop, _BLOCK):
        block = gens[i:min(i + _BLOCK, stop)]
        rows = scratch[:len(block)]
        if kind == "normal":
            for g, row in zip(block, rows):
                g.standard_normal(size, out=row)
        else:
            for g, row in zip(block, rows):
                g.random(size, out=row)
        out[:, i:i + len(block)] = rows.T


_THREADED_MIN = 64  # trials per thread below which a refill stays in one thread
_POOL: dict[int, ThreadPoolExecutor] = {}


def _pool(threads: int) -> ThreadPoolExecutor:
    """The process's pool of ``threads`` refill threads (made at its first threaded refill)."""
    if threads not in _POOL:
        _POOL[threads] = ThreadPoolExecutor(max_workers=threads, thread_name_prefix="aerodock-rng")
    return _POOL[threads]


def standard_normal_t(rng: np.random.Generator | TrialRNG, n: int, k: int) -> np.ndarray:
    """(k, n) standard normal draws for n trials, component-major: the numbers (and, for a plain
    ``Generator``, the order of drawing) of ``rng.standard_normal((n, k)).T``."""
    if isinstance(rng, TrialRNG) and rng.n == n:
        return rng._take("normal", k)
    return rng.standard_normal((n, k)).T
