"""A batch of N trials gives the same numbers as N single trials with the same seeds."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from aerodock.mission import MissionBatch, MissionSpec, Phase, run_campaign


def test_batch_equals_single_trials(short_cfg):
    cfg = short_cfg  # the property holds whatever the mission's timing (tests/short_mission.py)
    n = 2
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


def test_batch_equals_single_trials_with_a_learnt_model_in_the_loop(short_cfg):
    """With the model's feed-forward too: a trial's prediction does not depend on how many
    trials are predicted beside it (``aerodock.learning.runtime.ROW_BLOCK``; before, a trial
    alone and the same trial in a pair differed from the first period, by 1e-14 in the
    feed-forward)."""
    from aerodock.learning.runtime import Predictor

    model = Predictor.load(Path(__file__).parents[1] / "learning" / "data" / "kind_pins" / "so2")
    spec = {"compensation": "model", "seed": 11}
    batch = run_campaign(short_cfg, MissionSpec(trials=3, **spec), model, record="trace")
    for i in range(3):
        one = run_campaign(short_cfg, MissionSpec(trials=1, first_trial=i, **spec), model,
                           record="trace")
        steps = min(len(one.trace["t_s"]), len(batch.trace["t_s"]))
        for key in ("follower_p", "ff"):
            assert np.array_equal(one.trace[key][:steps, 0], batch.trace[key][:steps, i]), key
        assert one.err_down_m[0] == batch.err_down_m[i]


def test_terminal_window_figures_do_not_depend_on_the_batch(short_cfg):
    """Each trial's terminal-window figures (sums over the window's steps) are its own to the
    bit in a batch of one and of three (a sum over one trial's steps is not rounded otherwise
    than over several trials' steps)."""
    keys = ("err_down_m", "err_3d_m", "err_down_int_ms", "err_3d_int_ms", "ff_down_int_mps",
            "tilt_rms_deg", "saturated_frac")
    batch = run_campaign(short_cfg, MissionSpec(trials=3, compensation="oracle", seed=4))
    for i in range(3):
        one = run_campaign(short_cfg, MissionSpec(trials=1, compensation="oracle", seed=4,
                                                  first_trial=i))
        for key in keys:
            assert getattr(one, key)[0] == getattr(batch, key)[i], key


def test_same_seed_same_numbers_different_seed_different(short_cfg):
    cfg = short_cfg  # the property holds whatever the mission's timing (tests/short_mission.py)
    a = run_campaign(cfg, MissionSpec(trials=3, seed=5), record="trace")
    b = run_campaign(cfg, MissionSpec(trials=3, seed=5), record="trace")
    c = MissionBatch(cfg, MissionSpec(trials=3, seed=6), record="trace")
    for _ in range(50):  # the first 50 periods of seed 6 (all that is compared)
        c.fly()
    assert np.array_equal(a.trace["follower_p"], b.trace["follower_p"])
    assert not np.array_equal(a.trace["follower_p"][:50], c.result().trace["follower_p"][:50])


def test_a_trials_outcome_is_its_own_however_long_the_batch_flies(docking_cfg):
    """A trial that ended (docked and hung for post_dock_s, or backed off) is still simulated
    while its batch flies the others; what happens to it then is not its outcome. Without a model
    the hanging pair sinks (the follower does not answer the wake on it) and hits the ground
    later: each trial's outcome when the batch ends is its outcome on the period its own flight
    ended (where a campaign of it alone ends: the period after it is done), and the trial that
    ends first, flown alone, has the same outcome."""
    cfg = docking_cfg  # the mission's machinery, on a world where it docks (worlds.py)
    from aerodock.control.profiles import controller_config

    ours = controller_config(cfg, "ours")
    n = 6
    flying = MissionBatch(ours, MissionSpec(trials=n, compensation="observer", seed=1))
    own_end: dict[int, tuple[int, object]] = {}  # trial -> (period, its outcome then)
    while not flying.finished:
        done = flying.phase == Phase.DONE
        flying.fly()
        for i in np.nonzero(done)[0]:
            own_end.setdefault(int(i), (flying.k, flying.result().take([i])))
    batch = flying.result()
    assert batch.success.sum() >= 4  # our controller docks without the model ...
    sink = batch.summary()["post_dock_sink_median_m"]
    assert sink is not None and sink > 0.5  # ... but the pair it leaves hanging sinks
    first = min(own_end, key=lambda i: own_end[i][0])
    assert own_end[first][0] < flying.k  # the batch flew on after it
    alone = run_campaign(ours, MissionSpec(trials=1, compensation="observer", seed=1,
                                           first_trial=first))
    outcomes = [(i, own_end.get(i, (flying.k, batch.take([i])))[1]) for i in range(n)]
    for i, one in [*outcomes, (first, alone)]:
        for name in ("success", "rotor_strike", "ground_contact", "clearance_violation"):
            assert getattr(one, name)[0] == getattr(batch, name)[i], (i, name)
        assert np.array_equal(one.post_dock_sink_m, batch.post_dock_sink_m[i:i + 1],
                              equal_nan=True)


def test_armed_and_disarmed_trials_fly_as_in_their_own_campaigns(short_cfg):
    """Per-trial trigger flags: one batch flies the same trials armed and disarmed (as reproduce's
    moving-leader study does), and each half's outcomes equal its own campaign's."""
    cfg = short_cfg  # the property holds whatever the mission's timing (tests/short_mission.py)
    n = 3
    common = dict(offset_m=0.36, leader_speed_mps=0.25, compensation="observer", seed=7)
    armed = run_campaign(cfg, MissionSpec(trials=n, **common), record="trace")
    disarmed = run_campaign(cfg, MissionSpec(trials=n, passive_trigger=False,
                                             active_trigger=False, **common), record="trace")
    flags = (True,) * n + (False,) * n
    both = run_campaign(cfg, MissionSpec(trials=2 * n, passive_trigger=flags,
                                         active_trigger=flags, **common), record="trace",
                        trials=np.r_[0:n, 0:n])
    for alone, half in ((armed, both.take(np.arange(n))),
                        (disarmed, both.take(np.arange(n, 2 * n)))):
        assert half.summary() == alone.summary()
        steps = min(len(alone.trace["t_s"]), len(half.trace["t_s"]))
        for key in ("follower_p", "bar_p", "gate"):
            assert np.array_equal(half.trace[key][:steps], alone.trace[key][:steps]), key
    assert armed.success.any() and not disarmed.success.any()  # arming matters
    with pytest.raises(ValueError, match="one per trial"):
        run_campaign(cfg, MissionSpec(trials=2, passive_trigger=(True,)))
