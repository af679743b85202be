"""The mean of a downwash field, exact or estimated: the one helper for "what does this field do
on average here?".

A field may offer ``mean_acceleration(leader, follower)`` (the default jet does); a plug-in need
not. Whoever needs the mean (the oracle compensator, ``field probe``, ``field plot``, the error
floor of ``reproduce``, the simulator's recorded truth) asks :func:`mean_acceleration_fn`, which
returns the field's own method when it has one and otherwise an :class:`EstimatedMean`:

- the field is copied (``copy.deepcopy``, or a factory you pass), so the simulated trial's
  field, its turbulence state and its random stream are never touched;
- every query point is replicated ``samples`` times and the copy is reset to that many
  independent trials with its own random source, then ``acceleration`` is called ``steps``
  times at the step ``dt_s``; the estimate is the average over the replicas (and steps);
- the random numbers are *common*: every point uses the same ``samples`` turbulence draws,
  from a generator restarted from ``seed`` on every call. So the estimate at a point depends on
  that point only (not on the batch size, on the other points or on how often it was called),
  a batch of N trials reproduces N single trials bit for bit, and a plotted slice is smooth;
- the draws come in antithetic pairs (``z`` and ``-z``; ``u`` and ``1 - u``): turbulence that
  enters the field linearly (additive, or multiplicative on the mean, as in the default jet and
  most Ornstein-Uhlenbeck models) averages out exactly, so such a field's mean is recovered to
  rounding error.

For turbulence that enters non-linearly the error is at most about the field's turbulence sd
divided by ``sqrt(samples * steps)`` (fewer independent draws if the turbulence is correlated
across steps): with the default 64 samples and a 22 % sd, about 3 % of the mean. A field whose
output depends on its own history (not only on the current states and fresh noise) is estimated
as it behaves ``steps`` steps after ``reset``.
"""

from __future__ import annotations

import copy
from collections.abc import Callable
from typing import Any

import numpy as np

from aerodock.downwash.base import BodyState

MeanFn = Callable[[BodyState, BodyState], np.ndarray]

DEFAULT_SAMPLES = 64
DEFAULT_DT_S = 0.002  # the default physics step (500 Hz)
DEFAULT_SEED = 20251123
_MAX_ROWS = 1 << 16  # points x samples evaluated per call of the copied field


def has_mean(field: Any) -> bool:
    """True when the field offers its own ``mean_acceleration``."""
    return callable(getattr(field, "mean_acceleration", None))


def mean_acceleration_fn(field: Any, *, samples: int = DEFAULT_SAMPLES, steps: int = 1,
                         dt_s: float = DEFAULT_DT_S, seed: int = DEFAULT_SEED,
                         make_field: Callable[[], Any] | None = None) -> MeanFn:
    """``mean(leader, follower) -> (n, 3)`` m/s², NED: the field's own ``mean_acceleration`` if
    it has one, else an :class:`EstimatedMean` of it (see the module docstring).

    Args:
        field: a downwash field (``reset`` and ``acceleration`` at least).
        samples: independent turbulence samples per point (estimate only).
        steps: ``acceleration`` calls after each reset, averaged too (estimate only).
        dt_s: the step passed to ``acceleration``, s (estimate only).
        seed: seed of the estimator's own random source (estimate only).
        make_field: builds a fresh instance of the field (default: ``copy.deepcopy(field)``).
    """
    if has_mean(field):
        return field.mean_acceleration
    return EstimatedMean(field, samples=samples, steps=steps, dt_s=dt_s, seed=seed,
                         make_field=make_field)


def mean_source(mean_fn: MeanFn) -> str:
    """One line saying where a mean comes from (for reports and ``--json`` output)."""
    if isinstance(mean_fn, EstimatedMean):
        return mean_fn.description
    return "the field's mean_acceleration()"


class EstimatedMean:
    """The mean acceleration of a field without ``mean_acceleration``, by averaging ``acceleration``
    over independent turbulence samples on a private copy of the field (module docstring).

    Args: as :func:`mean_acceleration_fn`.

    Raises:
        ValueError: ``samples`` or ``steps`` below 1, ``dt_s`` not positive, or a field that can
            be neither deep-copied nor built by ``make_field``.
    """

    def __init__(self, field: Any, *, samples: int = DEFAULT_SAMPLES, steps: int = 1,
                 dt_s: float = DEFAULT_DT_S, seed: int = DEFAULT_SEED,
                 make_field: Callable[[], Any] | None = None):
        if samples < 1 or steps < 1:
            raise ValueError(f"mean estimate needs samples >= 1 and steps >= 1, got {samples}, "
                             f"{steps}")
        if not dt_s > 0:
            raise ValueError(f"mean estimate needs dt_s > 0, got {dt_s!r}")
        try:
            self._field = make_field() if make_field is not None else copy.deepcopy(field)
        except Exception as err:  # noqa: BLE001 - any copy failure becomes one clear message
            raise ValueError(f"cannot estimate the mean of {type(field).__name__}: the field "
                             f"cannot be copied ({err}); give it mean_acceleration()") from None
        self.samples = int(samples)
        self.steps = int(steps)
        self.dt_s = float(dt_s)
        self.seed = int(seed)
        self.description = (f"estimated: average of acceleration() over {self.samples} "
                            f"turbulence samples (antithetic pairs) x {self.steps} step(s) of "
                            f"{self.dt_s:g} s on a copy of the field (aerodock.downwash.mean)")

    def __call__(self, leader: BodyState, follower: BodyState) -> np.ndarray:
        """(n, 3) estimated mean acceleration on the follower, m/s², NED."""
        n = follower.n
        out = np.empty((n, 3))
        chunk = max(1, _MAX_ROWS // self.samples)
        for start in range(0, n, chunk):
            sel = slice(start, min(n, start + chunk))
            out[sel] = self._chunk(_rows(leader, sel), _rows(follower, sel))
        return out

    def _chunk(self, leader: BodyState, follower: BodyState) -> np.ndarray:
        n, s = follower.n, self.samples
        rows = n * s
        lead, fol = _repeat(leader, s), _repeat(follower, s)
        rng = CommonRandom(self.seed, s, rows)
        self._field.reset(rows, rng)
        total = np.zeros((rows, 3))
        for _ in range(self.steps):
            total += np.asarray(self._field.acceleration(lead, fol, self.dt_s), dtype=float)
        return total.reshape(n, s, 3).mean(axis=1) / self.steps


class CommonRandom:
    """A random source whose per-trial draws repeat every ``samples`` rows.

    For a draw whose leading size is ``rows`` (= points x samples, point-major), it draws
    ``samples`` rows from its own generator, half of them the antithetic mirror of the other
    half (``-z`` for a normal ``z``, ``1 - u`` for a uniform ``u``), and tiles them over the
    points; any other draw goes to the generator unchanged. Methods a field may use beyond
    ``standard_normal``, ``normal``, ``random`` and ``uniform`` are the generator's own.
    """

    def __init__(self, seed: int, samples: int, rows: int):
        self._gen = np.random.default_rng(seed)
        self.samples = samples
        self.rows = rows

    def _common(self, draw: Callable[..., np.ndarray], size: Any,
                mirror: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
        shape = (size,) if isinstance(size, int | np.integer) else tuple(size or ())
        if not shape or shape[0] != self.rows or self.rows % self.samples:
            return draw(size=size)
        half = self.samples // 2
        base = draw(size=(half, *shape[1:]))
        parts = [base, mirror(base)]
        if self.samples % 2:
            parts.append(draw(size=(1, *shape[1:])))
        block = np.concatenate(parts)
        return np.tile(block, (self.rows // self.samples,) + (1,) * (len(shape) - 1))

    def standard_normal(self, size: Any = None) -> np.ndarray:
        """Standard normal draws (common over the points, antithetic pairs ``z, -z``)."""
        return self._common(self._gen.standard_normal, size, np.negative)

    def normal(self, loc: Any = 0.0, scale: Any = 1.0, size: Any = None) -> np.ndarray:
        """Normal draws (common over the points, antithetic pairs)."""
        return loc + scale * self.standard_normal(size)

    def random(self, size: Any = None) -> np.ndarray:
        """Uniform draws in [0, 1) (common over the points, antithetic pairs ``u, 1 - u``)."""
        return self._common(self._gen.random, size, lambda u: 1.0 - u)

    def uniform(self, low: Any = 0.0, high: Any = 1.0, size: Any = None) -> np.ndarray:
        """Uniform draws in [low, high) (common over the points, antithetic pairs)."""
        return low + (high - low) * self.random(size)

    def __getattr__(self, name: str) -> Any:
        if name.startswith("_"):  # not set yet (copy, pickle): no recursion into _gen
            raise AttributeError(name)
        return getattr(self._gen, name)


def _rows(body: BodyState, sel: slice) -> BodyState:
    return BodyState(body.p[sel], body.v[sel], body.R[sel], body.thrust_n[sel], body.mass_kg[sel])


def _repeat(body: BodyState, k: int) -> BodyState:
    return BodyState(*(np.repeat(np.asarray(a, dtype=float), k, axis=0)
                       for a in (body.p, body.v, body.R, body.thrust_n, body.mass_kg)))
