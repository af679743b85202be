"""Per-trial random streams: a row draws its own (seed, trial) stream, whatever batch it is in."""

from __future__ import annotations

import numpy as np
import pytest

from aerodock.rng import TrialRNG


def _draws(rng: TrialRNG) -> np.ndarray:
    """Normal, uniform and more normal draws in one order, (n, 11)."""
    return np.concatenate([rng.standard_normal((rng.n, 4)), rng.random((rng.n, 2)),
                           rng.standard_normal_t(5).T], axis=1)


def test_several_campaigns_in_one_batch_draw_their_own_numbers():
    seeds, trials = np.array([3, 3, 8, 8, 11]), np.array([0, 1, 0, 1, 4])
    batch = _draws(TrialRNG(3, 5, trials=trials, seeds=seeds))
    for row, (seed, trial) in enumerate(zip(seeds, trials, strict=True)):
        alone = _draws(TrialRNG(int(seed), 1, first_trial=int(trial)))
        assert np.array_equal(batch[row], alone[0])
    same_seed = TrialRNG(3, 2, trials=[0, 1], seeds=[3, 3])  # as without seeds
    assert np.array_equal(_draws(same_seed), _draws(TrialRNG(3, 2)))
    assert np.array_equal(TrialRNG(3, 5, trials=trials, seeds=seeds).take_rows([2, 4]).seeds,
                          [8, 11])


def test_a_batch_of_several_seeds_refuses_shared_draws():
    rng = TrialRNG(0, 3, seeds=[0, 1, 2])
    with pytest.raises(ValueError, match="cannot draw shared numbers"):
        rng.standard_normal(7)
    assert TrialRNG(0, 3).standard_normal(7).shape == (7,)  # one campaign may
    with pytest.raises(ValueError, match="must hold 3 seeds"):
        TrialRNG(0, 3, seeds=[0, 1])


def test_a_refill_split_between_threads_draws_the_same_numbers(monkeypatch):
    """Large batches refill their streams in several threads: each trial's numbers are those
    its stream draws alone, whatever the split."""
    import aerodock.rng as rng_module

    monkeypatch.setattr(rng_module, "usable_cores", lambda: 3)
    monkeypatch.setattr(rng_module, "_THREADED_MIN", 20)
    batch = TrialRNG(3, 100)
    normals = batch.standard_normal_t(5000).copy()  # past a chunk: two refills
    uniforms = batch.random((100, 3)).copy()
    for trial in (0, 15, 16, 33, 34, 66, 99):  # either side of each thread's cut
        alone = TrialRNG(3, 1, trial)
        assert np.array_equal(alone.standard_normal_t(5000)[:, 0], normals[:, trial])
        assert np.array_equal(alone.random((1, 3))[0], uniforms[trial])
