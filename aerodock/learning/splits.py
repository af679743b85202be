"""Splitting a data set: validation flights or time blocks, held-out flights, minutes of data."""

from __future__ import annotations

import numpy as np

from aerodock.learning.dataset import DataError, Dataset


def _flight_counts(ds: Dataset) -> tuple[np.ndarray, np.ndarray]:
    ids, counts = np.unique(ds.flight_id, return_counts=True)
    return ids, counts


def flight_split_ids(
    ds: Dataset, val_fraction: float, rng: np.random.Generator, *, tries: int = 64
) -> np.ndarray | None:
    """Flight ids for a validation set holding about ``val_fraction`` of the samples.

    Random flight orders are filled greedily and the subset closest to the target is kept.
    Returns None when there are fewer than two flights (no flight split is possible).
    """
    ids, counts = _flight_counts(ds)
    if len(ids) < 2:
        return None
    target = val_fraction * counts.sum()
    best: np.ndarray | None = None
    best_err = np.inf
    for _ in range(tries):
        order = rng.permutation(len(ids))
        chosen, total = [], 0
        for k in order:
            if total + counts[k] <= 1.25 * target or not chosen:
                chosen.append(k)
                total += counts[k]
            if total >= target:
                break
        if len(chosen) == len(ids):
            chosen = chosen[:-1]
            total = counts[chosen].sum()
        err = abs(total - target)
        if err < best_err:
            best, best_err = ids[np.array(chosen)], err
    return best


def split_by_flight(
    ds: Dataset, val_fraction: float = 0.2, rng: np.random.Generator | None = None
) -> tuple[Dataset, Dataset]:
    """Split into (train, held-out) by whole flights, about ``val_fraction`` of samples held out.

    No flight appears in both parts; each part has at least one flight.

    Raises:
        DataError: fewer than two flights.
    """
    rng = np.random.default_rng(0) if rng is None else rng
    if not 0.0 < val_fraction < 1.0:
        raise ValueError(f"val_fraction must be in (0, 1), got {val_fraction}")
    val_ids = flight_split_ids(ds, val_fraction, rng)
    if val_ids is None:
        raise DataError("dataset: splitting by flight needs at least two flights")
    in_val = np.isin(ds.flight_id, val_ids)
    return ds.subset(~in_val), ds.subset(in_val)


def time_block_split_mask(
    ds: Dataset, val_fraction: float, rng: np.random.Generator, *, block_s: float = 5.0
) -> np.ndarray:
    """Boolean (n,) validation mask of whole contiguous time blocks (within each flight).

    Blocks of ``block_s`` seconds (shortened so that there are at least 10 blocks) are shuffled and
    taken until ``val_fraction`` of the samples is reached; blocks far longer than the wake's
    turbulence correlation time keep train and validation samples nearly independent.
    """
    span = sum(
        float(np.ptp(ds.t_s[ds.flight_id == k])) for k in np.unique(ds.flight_id)
    )
    block_s = max(min(block_s, span / 10.0), 1e-9)
    blocks = np.zeros(ds.n, dtype=np.int64)
    n_blocks = 0
    for k in np.unique(ds.flight_id):
        sel = ds.flight_id == k
        t = ds.t_s[sel]
        b = np.floor((t - t.min()) / block_s).astype(np.int64)
        _, b = np.unique(b, return_inverse=True)
        blocks[sel] = b.reshape(-1) + n_blocks
        n_blocks += int(b.max()) + 1
    counts = np.bincount(blocks, minlength=n_blocks)
    target = val_fraction * ds.n
    chosen, total = [], 0
    for k in rng.permutation(n_blocks):
        if total >= target or len(chosen) == n_blocks - 1:
            break
        chosen.append(k)
        total += counts[k]
    return np.isin(blocks, chosen)


def take_minutes(
    ds: Dataset, minutes: float, rng: np.random.Generator, *, mode: str = "flights"
) -> Dataset:
    """A subset holding ``minutes`` of flight time, as whole flights or contiguous chunks.

    Args:
        ds: the data.
        minutes: requested flight time; all of ``ds`` if it holds no more than that.
        rng: random generator (which flights, where the chunks start).
        mode: ``"flights"`` (default): whole flights in random order, the last one cut to a
            contiguous chunk at a random offset to hit the requested time. ``"stratified"``:
            one contiguous chunk from every flight, each the same fraction of its flight (keeps
            the mix of separations of the full data, e.g. every curriculum stage).

    Raises:
        ValueError: ``minutes`` not positive, or unknown mode.
    """
    if not minutes > 0:
        raise ValueError(f"minutes must be positive, got {minutes}")
    if mode not in ("flights", "stratified"):
        raise ValueError(f"unknown mode {mode!r} (expected 'flights' or 'stratified')")
    if minutes >= ds.minutes:
        return ds
    ids = np.unique(ds.flight_id)
    dt = np.array([float(ds.meta["flights"][k].get("dt_s", 0.0)) for k in ids])
    index_of = {k: np.flatnonzero(ds.flight_id == k) for k in ids}
    chosen: list[np.ndarray] = []

    def chunk(k: int, n_take: int) -> np.ndarray:
        idx = index_of[k]
        idx = idx[np.argsort(ds.t_s[idx], kind="stable")]
        n_take = max(1, min(n_take, len(idx)))
        start = int(rng.integers(0, len(idx) - n_take + 1))
        return idx[start:start + n_take]

    if mode == "stratified":
        frac = minutes / ds.minutes
        for k in ids:
            chosen.append(chunk(k, int(round(frac * len(index_of[k])))))
    else:
        remaining_s = minutes * 60.0
        for j in rng.permutation(len(ids)):
            k = ids[j]
            flight_s = len(index_of[k]) * dt[j]
            if flight_s <= remaining_s:
                chosen.append(index_of[k])
                remaining_s -= flight_s
            else:
                n_take = int(round(remaining_s / dt[j])) if dt[j] > 0 else len(index_of[k])
                if n_take > 0:
                    chosen.append(chunk(k, n_take))
                remaining_s = 0.0
            if remaining_s <= 0.0:
                break
    return ds.subset(np.sort(np.concatenate(chosen)))
