"""The docking environments: Gymnasium's checks, the mission they fly, and batch = single."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

gym = pytest.importorskip("gymnasium")

from gymnasium.utils.env_checker import check_env  # noqa: E402
from gymnasium.vector import SyncVectorEnv  # noqa: E402

from aerodock.envs import ENV_ID, DockingEnv, DockingVectorEnv  # noqa: E402
from aerodock.envs.check import check_vector_env  # noqa: E402
from aerodock.mission import AbortReason, MissionSpec, run_campaign  # noqa: E402
from aerodock.mission.checks import MissionSpecError  # noqa: E402


def test_single_env_passes_gymnasium_check_env(short_cfg):
    # (the checks hold whatever the mission's timing: the short one, tests/short_mission.py)
    env = gym.make(ENV_ID, render_mode="rgb_array", config=short_cfg)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a checker warning fails the test too
        check_env(env.unwrapped)
    frame = env.unwrapped.render()
    assert frame.ndim == 3 and frame.shape[2] == 3 and frame.dtype == np.uint8


def test_vector_env_passes_the_vector_checks_and_gymnasium_wrappers(short_cfg):
    # (the API holds whatever the mission's timing: the short one, tests/short_mission.py)
    env = gym.make_vec(ENV_ID, num_envs=3, vectorization_mode="vector_entry_point",
                       config=short_cfg)
    assert isinstance(env.unwrapped, DockingVectorEnv)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_vector_env(env)
        # Gymnasium's vector wrappers accept its autoreset mode.
        wrapped = gym.wrappers.vector.RecordEpisodeStatistics(env)
        wrapped.reset(seed=0)
        wrapped.step(wrapped.action_space.sample())


def test_zero_residual_flies_run_campaigns_mission(short_cfg):
    """With no residual, each trial's outcome and clearance are those of run_campaign (whatever
    the mission's timing: the short one, tests/short_mission.py)."""
    cfg = short_cfg
    n, seed = 4, 3
    env = DockingVectorEnv(num_envs=n, campaign_seed=seed, compensation="oracle", config=cfg)
    env.reset(seed=0)
    docked = np.zeros(n, bool)
    missed = np.zeros(n, bool)
    aborted = np.zeros(n, bool)
    ret = np.zeros(n)
    for _ in range(env.batch.max_steps + 1):
        _, rew, term, trunc, info = env.step(np.zeros((n, 3)))
        ret += rew
        docked |= info["docked"]
        missed |= info["missed"]
        aborted |= info["aborted"]
        if term.any() or trunc.any():
            break
    res = run_campaign(cfg, MissionSpec(trials=n, seed=seed, compensation="oracle"))
    # Every trial ends on this step: truncated if its docking window closed, else terminated.
    np.testing.assert_array_equal(trunc, res.abort_reason == AbortReason.TIMEOUT)
    np.testing.assert_array_equal(term, ~trunc)
    np.testing.assert_array_equal(docked, res.success)
    np.testing.assert_array_equal(missed, res.missed)
    np.testing.assert_array_equal(aborted, res.aborted)
    np.testing.assert_allclose(info["min_clearance_m"], res.min_clearance_m, rtol=0, atol=0)
    # Docked trials earn the dock reward (less the small dense costs).
    assert np.all(ret[res.success] > 8.0) and np.all(ret[~res.success] < 0.0)
    # The next step autoresets the whole batch onto the next trials.
    obs, rew, term, trunc, info = env.step(np.zeros((n, 3)))
    assert not rew.any() and not term.any() and not trunc.any()
    np.testing.assert_array_equal(info["trial"], np.arange(n, 2 * n))


def test_vector_env_equals_sync_vector_env_of_single_envs(short_cfg):
    """Sub-environment i of the native vector env is DockingEnv reset with seed s + i."""
    n, s = 3, 10
    kwargs = {"campaign_seed": 1, "compensation": "observer", "leader_speed_mps": 0.25,
              "config": short_cfg}
    native = DockingVectorEnv(num_envs=n, **kwargs)
    sync = SyncVectorEnv([lambda: DockingEnv(**kwargs) for _ in range(n)])
    o1, _ = native.reset(seed=s)
    o2, _ = sync.reset(seed=s)
    np.testing.assert_array_equal(o1, o2)
    rng = np.random.default_rng(0)
    for _ in range(60):
        act = rng.uniform(-1, 1, (n, 3)).astype(np.float32)
        a, ra, ta, _, ia = native.step(act)
        b, rb, tb, _, ib = sync.step(act)
        np.testing.assert_array_equal(a, b)
        np.testing.assert_array_equal(ra, rb)
        np.testing.assert_array_equal(ta, tb)
        np.testing.assert_array_equal(ia["phase"], ib["phase"])


def test_residual_changes_the_flight_and_leader_dropout_aborts(short_cfg):
    # (whatever the mission's timing: the short one, tests/short_mission.py)
    env = DockingEnv(campaign_seed=0, leader_dropout_s=(1.0, 2.0), config=short_cfg)
    obs0, _ = env.reset(seed=5)
    push = np.array([0.0, 0.0, -1.0], dtype=np.float32)  # up, 2 m/s²
    for _ in range(30):
        obs_push, *_ = env.step(push)
    env.reset(seed=5)
    for _ in range(30):
        obs_zero, *_ = env.step(np.zeros(3, np.float32))
    # Tracking error down (index 2) is smaller when pushed up.
    assert obs_push[2] < obs_zero[2] - 0.01
    info = {}
    for _ in range(env.batch.max_steps):
        _, _, term, trunc, info = env.step(np.zeros(3, np.float32))
        if term or trunc:
            break
    assert term and info["abort_reason"] == 2  # AbortReason.LEADER_LOST


def run_episode(env, policy, seed):
    """Reset ``env`` with ``seed`` and step ``policy()`` until the episode ends."""
    env.reset(seed=seed)
    for k in range(env.batch.max_steps + 1):
        _, _, term, trunc, info = env.step(policy())
        if term or trunc:
            return k + 1, term, trunc, info
    raise AssertionError("the episode did not end")


def test_time_out_is_truncated_and_a_dock_terminated(short_cfg):
    """An approach whose docking window closes undocked is a time-out: truncated, not
    terminated (the mission's timeout abort); a docked trial is terminated."""
    env = DockingEnv(campaign_seed=0, config=short_cfg)
    rng = np.random.default_rng(0)
    steps, term, trunc, info = run_episode(
        env, lambda: rng.uniform(-1, 1, 3).astype(np.float32), 0)
    assert trunc and not term
    assert info["abort_reason"] == AbortReason.TIMEOUT and info["aborted"]
    # It ends on the step the docking window closes.
    assert steps * env.batch.dt_s == pytest.approx(env.batch.mission.timing.timeout_s)
    env = DockingEnv(campaign_seed=0, compensation="oracle", config=short_cfg)
    _, term, trunc, info = run_episode(env, lambda: np.zeros(3, np.float32), 0)
    assert term and not trunc and info["docked"]


def test_non_finite_actions_raise(short_cfg):
    env = DockingEnv(config=short_cfg)  # (the short timing: tests/short_mission.py)
    env.reset(seed=0)
    for bad in (np.nan, np.inf, -np.inf):
        with pytest.raises(ValueError, match="NaN or infinite"):
            env.step(np.array([0.0, bad, 0.0], dtype=np.float32))
    with pytest.raises(ValueError, match="shape"):
        env.step(np.zeros(4, np.float32))
    venv = DockingVectorEnv(num_envs=2, config=short_cfg)
    venv.reset(seed=0)
    act = np.zeros((2, 3), np.float32)
    act[1, 2] = np.nan
    with pytest.raises(ValueError, match=r"NaN or infinite values \(rows \[1\]\)"):
        venv.step(act)
    # A refused action flies nothing: the next finite step is the first period.
    _, _, _, _, info = env.step(np.zeros(3, np.float32))
    assert info["t_s"] == pytest.approx(env.batch.dt_s)


def test_step_before_reset_raises_a_clear_error():
    with pytest.raises(RuntimeError, match=r"call reset\(\) before step\(\)"):
        DockingEnv().step(np.zeros(3, np.float32))
    with pytest.raises(RuntimeError, match=r"call reset\(\) before step\(\)"):
        DockingVectorEnv(num_envs=2).step(np.zeros((2, 3), np.float32))


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"leader_speed_mps": 1e9}, "leader_speed_mps must be between -100 and 100"),
    ({"leader_speed_mps": float("nan")}, "leader_speed_mps must be a finite number"),
    ({"leader_speed_mps": "fast"}, "leader_speed_mps must be a number"),
    ({"residual_max_mps2": float("inf")}, "residual_max_mps2 must be a finite number"),
    ({"residual_max_mps2": float("nan")}, "residual_max_mps2 must be a finite number"),
    ({"residual_max_mps2": 0.0}, "residual_max_mps2 must be > 0"),
    ({"residual_max_mps2": -2.0}, "residual_max_mps2 must be > 0"),
    ({"residual_max_mps2": 1e6}, "residual_max_mps2 must be between 0 and 50"),
    ({"campaign_seed": -1}, "campaign_seed must be an integer >= 0"),
    ({"campaign_seed": 1.5}, "campaign_seed must be an integer >= 0"),
    ({"leader_fixed": "yes"}, "leader_fixed must be True or False"),
    ({"compensation": "magic"}, "compensation must be one of"),
    ({"offset_m": float("inf")}, "offset_m must be a finite number"),
    ({"leader_dropout_s": (1.0, -2.0)}, "leader_dropout_s"),
    ({"reward_weights": {"dock": float("nan")}}, "reward_weights.dock must be a finite"),
    ({"reward_weights": {"bonus": 1.0}}, "reward_weights: unknown fields"),
])
def test_env_parameters_are_checked_like_the_command_line(kwargs, message):
    for make in (lambda: DockingEnv(**kwargs), lambda: DockingVectorEnv(num_envs=2, **kwargs)):
        with pytest.raises(MissionSpecError, match=message):
            make()


def test_bad_arguments_are_refused():
    with pytest.raises(ValueError, match="needs a predictor"):
        DockingEnv(compensation="model")
    with pytest.raises(ValueError, match="offset_m"):
        DockingEnv(offset_m=-1.0)
    with pytest.raises(ValueError, match="num"):
        DockingVectorEnv(num_envs=0)


def test_residual_example_quick_mode_trains_and_evaluates(short_cfg):
    """examples/residual_ars.py in quick mode, one ARS iteration; its baseline is run_campaign's
    LQG mission. (Its plumbing, whatever the mission's timing: its environments fly the short one
    of tests/short_mission.py, through the example's ENV_KWARGS.)"""
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[2] / "examples" / "residual_ars.py"
    spec = importlib.util.spec_from_file_location("residual_ars", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    mod.ENV_KWARGS["config"] = short_cfg
    result = mod.main(["--quick", "--iterations", "1"])
    assert len(result["training"]) == result["settings"]["iterations"] == 1
    assert result["weights_norm"] > 0  # ARS moved the policy
    n = result["settings"]["eval_trials"]
    base = run_campaign(short_cfg, MissionSpec(trials=n, seed=0, offset_m=0.36,
                                         compensation="observer",
                                         first_trial=mod.HELDOUT_FIRST_TRIAL))
    assert result["baseline_lqg"]["docked_rate"] == base.success.mean()
    assert result["baseline_lqg"]["aborted_rate"] == base.aborted.mean()
    for key in ("baseline_lqg", "residual_policy"):
        r = result[key]
        assert r["docked_rate"] + r["missed_rate"] + r["aborted_rate"] == pytest.approx(1.0)


def test_bench_vector_env_figures(short_cfg, benchmark):
    """The bench's env-steps/s figures exist for both batch sizes (speed is measured by
    `aerodock bench`, not asserted here; the short timing of tests/short_mission.py: a shorter
    settled start on each reset)."""
    from aerodock import bench
    from aerodock.bench.vector_env import bench_vector_env

    figs = benchmark.pedantic(bench_vector_env, args=(short_cfg, (1, 8), True), rounds=1,
                              iterations=1)
    assert set(figs) == {"1", "8"} and all(f["value"] > 0 for f in figs.values())
    rows = bench.table_rows({"figures": {"gym_vector_env": figs}})
    assert [r[0] for r in rows] == ["gym vector env, 1 envs", "gym vector env, 8 envs"]
