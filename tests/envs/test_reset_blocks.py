"""DockingEnv's resets served from a block of settled starts: the same episodes, bit for bit, as
resets that settle their own trial; which resets a block serves; when blocks are off."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("gymnasium")

from aerodock.control.compensation import OraclePredictor  # noqa: E402
from aerodock.downwash import build_field  # noqa: E402
from aerodock.envs import DockingEnv  # noqa: E402


def _resets(env):
    """A training loop's resets and an evaluation loop's: a seed, two resets without one, the
    next seed, an explicit trial, the first seed again."""
    yield env.reset(seed=3)
    yield env.reset()
    yield env.reset()
    yield env.reset(seed=4)
    yield env.reset(options={"trial": 4})
    yield env.reset(seed=3)


def test_served_resets_fly_the_episodes_of_resets_that_settle_their_own_trial(short_cfg):
    # (equal whatever the mission's timing: the short one, tests/short_mission.py)
    kwargs = {"campaign_seed": 2, "leader_speed_mps": 0.25, "config": short_cfg}
    served, alone = DockingEnv(settle_block=6, **kwargs), DockingEnv(settle_block=1, **kwargs)
    rng = np.random.default_rng(0)
    for (o1, i1), (o2, i2) in zip(_resets(served), _resets(alone), strict=True):
        np.testing.assert_array_equal(o1, o2)
        assert i1 == i2
        for _ in range(25):
            act = rng.uniform(-1, 1, 3).astype(np.float32)
            s1, s2 = served.step(act), alone.step(act)
            np.testing.assert_array_equal(s1[0], s2[0])
            assert s1[1:] == s2[1:]
    # One block served every reset: the draws of np_random and the next seed were in it.
    assert served.starts.blocks == 1 and served.starts.served == 5
    assert alone.starts.blocks == 0 and not alone.starts.enabled


def test_a_served_episode_ends_as_its_own_does(short_cfg):
    served = DockingEnv(settle_block=4, config=short_cfg)
    alone = DockingEnv(settle_block=1, config=short_cfg)
    for env in (served, alone):
        env.reset(seed=0)
        env.reset()  # served from the first block
    assert served.starts.served == 1
    ends = []
    for env in (served, alone):
        total = 0.0
        for _ in range(env.batch.max_steps + 1):
            obs, rew, term, trunc, info = env.step(np.zeros(3, np.float32))
            total += rew
            if term or trunc:
                break
        ends.append((obs, total, term, trunc, info))
    np.testing.assert_array_equal(ends[0][0], ends[1][0])
    assert ends[0][1:] == ends[1][1:]


def test_a_reset_outside_the_block_settles_a_new_one(short_cfg):
    env = DockingEnv(settle_block=3, config=short_cfg)
    env.reset(seed=10)  # block: 10, 11 and the first draw after seed 10
    env.reset(seed=11)
    assert (env.starts.blocks, env.starts.served) == (1, 1)
    env.reset(seed=50)
    assert (env.starts.blocks, env.starts.served) == (2, 1)


def test_blocks_are_off_where_a_trial_settled_in_a_block_could_differ(short_cfg):
    """A learnt feed-forward (its matrix products round with the batch's shape) and a plug-in
    field that cannot split its state: each reset settles its own trial (whatever the mission's
    timing: the short one, tests/short_mission.py)."""
    cfg = short_cfg
    model = DockingEnv(compensation="model", predictor=OraclePredictor(build_field(cfg)),
                       config=cfg)
    plug_in = DockingEnv(config=cfg.with_overrides(
        {"downwash": {"field": "aerodock.downwash.template:UniformColumnField"}}))
    for env in (model, plug_in):
        env.reset(seed=0)
        assert not env.starts.enabled and env.starts.blocks == 0


@pytest.mark.parametrize("bad", [0, -1, 1.5, True, "8", 10**6])
def test_settle_block_is_checked(bad):
    with pytest.raises(ValueError, match="settle_block must be an integer from 1 to"):
        DockingEnv(settle_block=bad)


def test_bench_env_reset_figures(short_cfg, benchmark):
    """The bench's reset figures exist and count what they timed (the cost is measured by
    `aerodock bench --only gym` or `python -m aerodock.bench.env_reset`, not asserted here; the
    counts do not depend on the settled start's length: the short one, tests/short_mission.py)."""
    from aerodock import bench
    from aerodock.bench.env_reset import bench_env_reset

    figs = benchmark.pedantic(bench_env_reset, args=(short_cfg, 4, True), rounds=1, iterations=1)
    counts = figs.pop("block_counts")
    assert counts["resets"] == 2 * 8 == counts["blocks_settled"] + counts["served"]
    assert counts["served"] >= counts["resets"] // 2
    assert all(f["value"] > 0 and f["unit"] == "s" for f in figs.values())
    rows = bench.table_rows({"figures": {"gym_env_reset": figs}})
    assert [r[0] for r in rows] == [
        "gym env reset, its trial settled alone", "gym env reset, settling a block",
        "gym env reset, served from the block", "gym env reset, mean over a training loop"]
