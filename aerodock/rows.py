"""Some trials (rows) of a batch: the same state, as if only those trials had been flown.

A trial's numbers do not depend on the batch it flies in (per-trial random streams, row-wise
arithmetic), so the state of trial ``k`` in a batch of many is the state of trial ``k`` flown
alone. Taking rows is how one batch-first computation serves several single trials: the
environments settle a block of upcoming trials in one call and start each later episode from its
row (:mod:`aerodock.envs.starts`).

Batch state classes whose arrays are not all batch-first (component-major ``(3, n)`` arrays,
leaders-first ``2n`` batches, random streams, shared constants) have a ``take_rows(rows)``
method of their own; :func:`take_rows` handles the rest.
"""

from __future__ import annotations

import dataclasses
from typing import Any, TypeVar

import numpy as np

T = TypeVar("T")


def take_rows(value: T, rows: np.ndarray) -> T:
    """``value`` restricted to the trials ``rows`` (indices into its leading, per-trial axis).

    For batch state only, every array in it holding the trials on its leading axis: an array
    becomes ``value[rows]`` (a copy); an object with a ``take_rows`` method answers for itself; a
    dataclass, list or tuple is rebuilt from its taken members; anything else (a number, a
    string, None) is kept.
    """
    if isinstance(value, np.ndarray):
        return value[rows]
    if hasattr(value, "take_rows"):
        return value.take_rows(rows)
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return dataclasses.replace(value, **{f.name: take_rows(getattr(value, f.name), rows)
                                             for f in dataclasses.fields(value) if f.init})
    if isinstance(value, list):
        return [take_rows(v, rows) for v in value]
    if isinstance(value, tuple):
        return tuple(take_rows(v, rows) for v in value)
    return value


def pair_rows(rows: np.ndarray, n: int) -> np.ndarray:
    """The rows of a leaders-first batch of ``2n`` vehicles that belong to trials ``rows``:
    ``rows`` (their leaders) then ``n + rows`` (their followers)."""
    rows = np.asarray(rows, dtype=np.int64)
    return np.concatenate([rows, n + rows])


def as_rows(rows: Any, n: int) -> np.ndarray:
    """``rows`` as a 1-D int64 index array into a batch of ``n`` trials.

    Raises:
        ValueError: not a 1-D sequence of indices in ``[0, n)``.
    """
    out = np.asarray(rows)
    if out.ndim != 1 or out.size == 0 or not np.issubdtype(out.dtype, np.integer):
        raise ValueError(f"rows must be a non-empty 1-D array of integer indices, got {rows!r}")
    if out.min() < 0 or out.max() >= n:
        raise ValueError(f"rows must lie in [0, {n}), got {out.tolist()}")
    return out.astype(np.int64)
