"""A trial's settled start is its own: taken out of a block of trials settled together it equals
the trial settled alone, every array bit for bit, and the mission flown from it is the same."""

from __future__ import annotations

import dataclasses
from dataclasses import replace

import numpy as np
import pytest

from aerodock.control.profiles import controller_config
from aerodock.mission import MissionBatch, MissionSpec, settle_trials
from aerodock.world.state import WorldState

# Kept only within one physics step or one call, keyed by the objects of that step, or numbers
# derived from constants, keyed by the arrays they were computed for: not state. (A dataclass's
# state is its fields: what else its __dict__ holds are such numbers.)
_PER_STEP = {"_lead_key", "_lead_wake", "_body_key", "_body_force", "_points", "_offsets_obj",
             "_coeff", "_mean_fn", "mean_fn"}


def assert_same_state(a, b, path="start"):
    """Every array, number and random stream reachable from ``a`` equals ``b``'s."""
    if isinstance(a, np.ndarray):
        assert isinstance(b, np.ndarray) and a.shape == b.shape and a.dtype == b.dtype, path
        assert np.array_equal(a, b, equal_nan=a.dtype.kind in "fc"), path
    elif isinstance(a, np.random.Generator):
        assert a.bit_generator.state == b.bit_generator.state, path
    elif isinstance(a, list | tuple):
        assert type(a) is type(b) and len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            assert_same_state(x, y, f"{path}[{i}]")
    elif isinstance(a, dict):
        assert a.keys() == b.keys(), path
        for k in a:
            assert_same_state(a[k], b[k], f"{path}[{k!r}]")
    elif isinstance(a, WorldState):  # the 2n batch, however it is held (whole or in halves)
        assert_same_state(a.both, b.both, f"{path}.both")
        for f in dataclasses.fields(a):
            if f.name not in ("_both", "_lead", "_fol"):
                assert_same_state(getattr(a, f.name), getattr(b, f.name), f"{path}.{f.name}")
    elif hasattr(a, "__dict__") and not callable(a) and not isinstance(a, type):
        assert type(a) is type(b), path
        if type(a).__module__.startswith("aerodock.config"):
            return  # the configuration: the same file for both
        names = ({f.name for f in dataclasses.fields(a)} if dataclasses.is_dataclass(a)
                 else vars(a).keys())
        for k in names - _PER_STEP:
            assert_same_state(vars(a)[k], vars(b)[k], f"{path}.{k}")
    elif isinstance(a, float | int | str | bool | np.generic) or a is None:
        assert a == b or (a != a and b != b), (path, a, b)


def _variants(cfg):
    """(name, config, spec) of every kind of batch state: vehicle models, IMU chains, estimators,
    the controller profiles, leader modes and compensations."""
    spec = MissionSpec(trials=1, seed=4)
    return [
        ("default", cfg, spec),
        ("oracle, moving leader", cfg, replace(spec, compensation="oracle",
                                               leader_speed_mps=0.5)),
        ("point mass, no compensation", cfg.with_overrides({"vehicle": {"model": "point-mass"}}),
         replace(spec, compensation="none")),
        ("ideal IMU, leader on a stand", cfg.with_overrides({"imu": {"chain": "ideal"}}),
         replace(spec, leader_fixed=True)),
        ("paper controller (Freyja estimator)", controller_config(cfg, "paper"), spec),
        ("our controller (accelerometer), Freyja state filter",
         controller_config(cfg, "ours").with_overrides({"control": {"state_filter": "freyja"}}),
         spec),
    ]


@pytest.mark.parametrize("index", range(6))
def test_a_trial_taken_from_a_block_equals_the_trial_settled_alone(short_cfg, index):
    # equality holds whatever the mission's timing: the short one (tests/short_mission.py)
    name, config, spec = _variants(short_cfg)[index]
    block_trials = np.array([7, 3, 12, 5])
    block = settle_trials(config, replace(spec, trials=4), trials=block_trials)
    assert block.splittable, name
    taken = block.take_rows([2])
    alone = settle_trials(config, spec, trials=np.array([12]))
    assert_same_state(taken, alone)
    # Taking rows leaves the block as it was: another row, then the same row again.
    assert_same_state(block.take_rows([2]), alone)
    assert block.take_rows([0, 3]).trials.tolist() == [7, 5]
    if index != 1:
        # The mission flown from the taken start: the oracle's with a moving leader (the most
        # state: the predictor, the cruise). The default variant's (hover, bias observer) is
        # tests/envs/test_reset_blocks.py::test_a_served_episode_ends_as_its_own_does: a
        # DockingEnv episode from a row of a block (take_rows, MissionBatch(settled=...)) to its
        # end against the trial's own settled start.
        return
    one = replace(spec, first_trial=12)
    flown = [MissionBatch(config, one, settled=taken), MissionBatch(config, one)]
    traces = [[], []]
    while not flown[1].finished:
        for mb, trace in zip(flown, traces, strict=True):
            mb.fly()
            trace.append(np.concatenate([mb.world.follower.p, mb.world.leader.p,
                                         mb.world.bar.p], axis=1))
    assert flown[0].finished
    assert np.array_equal(np.array(traces[0]), np.array(traces[1]))
    a, b = (mb.result() for mb in flown)
    assert a.success[0] == b.success[0] and a.abort_reason[0] == b.abort_reason[0]


def test_a_settled_start_must_be_of_the_missions_trials(cfg):
    block = settle_trials(cfg, MissionSpec(trials=2, seed=1), trials=np.array([0, 1]))
    with pytest.raises(ValueError, match="not of these trials"):
        MissionBatch(cfg, MissionSpec(trials=1, seed=1, first_trial=5),
                     settled=block.take_rows([0]))
    with pytest.raises(ValueError, match="rows must lie in"):
        block.take_rows([2])
