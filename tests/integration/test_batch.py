"""A batch of N trials gives the same numbers as N single trials with the same seeds."""

from __future__ import annotations

import numpy as np

from aerodock.mission import MissionSpec, run_campaign


def test_batch_equals_single_trials(cfg):
    n = 4
    batch = run_campaign(cfg, MissionSpec(trials=n, compensation="oracle", seed=11),
                         record="trace")
    for i in range(n):
        one = run_campaign(cfg, MissionSpec(trials=1, compensation="oracle", seed=11,
                                            first_trial=i), record="trace")
        steps = min(len(one.trace["t_s"]), len(batch.trace["t_s"]))
        for key in ("follower_p", "leader_p", "bar_p", "ff"):
            assert np.array_equal(one.trace[key][:steps, 0], batch.trace[key][:steps, i]), key
        assert one.success[0] == batch.success[i]
        assert one.err_down_m[0] == batch.err_down_m[i]


def test_same_seed_same_numbers_different_seed_different(cfg):
    a = run_campaign(cfg, MissionSpec(trials=3, seed=5), record="trace")
    b = run_campaign(cfg, MissionSpec(trials=3, seed=5), record="trace")
    c = run_campaign(cfg, MissionSpec(trials=3, seed=6), record="trace")
    assert np.array_equal(a.trace["follower_p"], b.trace["follower_p"])
    assert not np.array_equal(a.trace["follower_p"][:50], c.trace["follower_p"][:50])
