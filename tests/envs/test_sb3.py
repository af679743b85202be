"""Stable-Baselines3 on the native vector environment (skipped without stable-baselines3):
the VecEnv API, the lockstep episode ends, and a short PPO run."""

from __future__ import annotations

import numpy as np
import pytest
from short_mission import short_config

pytest.importorskip("gymnasium")
pytest.importorskip("stable_baselines3")

from stable_baselines3 import PPO  # noqa: E402
from stable_baselines3.common.env_checker import check_env  # noqa: E402
from stable_baselines3.common.logger import Logger  # noqa: E402
from stable_baselines3.common.vec_env import DummyVecEnv, VecEnv, VecMonitor  # noqa: E402

from aerodock.envs import DockingEnv, DockingVectorEnv  # noqa: E402
from aerodock.envs.sb3 import DockingSB3VecEnv  # noqa: E402

# The API and the lockstep hold whatever the mission's timing: the short one (fewer simulated
# seconds per settled start and episode; tests/short_mission.py).
KWARGS = {"campaign_seed": 1, "leader_speed_mps": 0.25, "config": short_config()}


def test_single_env_passes_stable_baselines3_check_env():
    check_env(DockingEnv(**KWARGS), warn=True)


def test_sub_environments_are_make_vec_envs_single_environments():
    """Seeded alike, the adapter's N trials are DummyVecEnv's N DockingEnvs, step for step
    (until the first trial is decided: then the batch waits for the others)."""
    n = 3
    env = DockingSB3VecEnv(DockingVectorEnv(num_envs=n, **KWARGS))
    dummy = DummyVecEnv([lambda: DockingEnv(**KWARGS) for _ in range(n)])
    assert isinstance(env, VecEnv)
    assert env.observation_space == dummy.observation_space
    assert env.action_space == dummy.action_space
    assert env.seed(7) == dummy.seed(7) == [7, 8, 9]
    np.testing.assert_array_equal(env.reset(), dummy.reset())
    assert [i["trial"] for i in env.reset_infos] == [7, 8, 9]
    rng = np.random.default_rng(0)
    for _ in range(40):
        act = rng.uniform(-1, 1, (n, 3)).astype(np.float32)
        a, b = env.step(act), dummy.step(act)
        for x, y in zip(a[:3], b[:3], strict=True):
            np.testing.assert_array_equal(x, y)
        assert [i["phase"] for i in a[3]] == [i["phase"] for i in b[3]]
    # Seeds that are not consecutive fly those trials.
    env.seed(0)
    env._seeds = [5, 2, 5]
    env.reset()
    assert [i["trial"] for i in env.reset_infos] == [5, 2, 5]


def test_episodes_end_together_with_terminal_observations_and_the_next_trials_start():
    n = 2
    kwargs = {**KWARGS, "leader_dropout_s": (0.3, 2.0)}  # the leader is lost: the trials abort
    native = DockingVectorEnv(num_envs=n, **kwargs)
    env = VecMonitor(DockingSB3VecEnv(DockingVectorEnv(num_envs=n, **kwargs)))
    native.reset(seed=20)
    env.seed(20)
    env.reset()
    returns = np.zeros(n)
    zeros = np.zeros((n, 3), np.float32)
    for _ in range(native.batch.max_steps + 1):
        obs_n, rew_n, term, trunc, info_n = native.step(zeros)
        obs, rew, done, infos = env.step(zeros)
        returns += rew_n
        np.testing.assert_allclose(rew, rew_n.astype(np.float32))
        if done.any():
            break
        np.testing.assert_array_equal(obs, obs_n)
        assert [i["waiting"] for i in infos] == info_n["waiting"].tolist()
    assert done.all() and np.array_equal(done, term | trunc)
    for i in range(n):
        np.testing.assert_array_equal(infos[i]["terminal_observation"], obs_n[i])
        assert infos[i]["TimeLimit.truncated"] == bool(trunc[i] and not term[i])
        assert infos[i]["abort_reason"] == 2  # AbortReason.LEADER_LOST
        assert infos[i]["episode"]["r"] == pytest.approx(returns[i], rel=1e-5)
    # The observations returned are the next trials' first: the native autoreset's.
    obs_next, *_, info_next = native.step(zeros)
    np.testing.assert_array_equal(obs, obs_next)
    assert info_next["trial"].tolist() == [22, 23]
    assert [i["trial"] for i in env.unwrapped.reset_infos] == [22, 23]


def test_the_batch_answers_for_every_index():
    env = DockingSB3VecEnv(DockingVectorEnv(num_envs=2, config=KWARGS["config"]))
    assert env.get_attr("num_envs") == [2, 2] and env.get_attr("num_envs", 1) == [2]
    assert env.env_is_wrapped(VecMonitor) == [False, False]
    assert env.env_method("reset", seed=3)[0][1]["trial"].tolist() == [3, 4]
    with pytest.raises(TypeError, match="DockingVectorEnv"):
        DockingSB3VecEnv(DockingEnv())
    with pytest.raises(RuntimeError, match="step_async"):
        env.step_wait()
    env.set_options([{"trial": 1}, {"trial": 2}])
    with pytest.raises(ValueError, match="one set of reset options"):
        env.reset()
    env.close()


def test_ppo_trains_a_few_hundred_steps_on_the_native_vector_env():
    torch = pytest.importorskip("torch")
    torch.set_num_threads(1)
    env = VecMonitor(DockingSB3VecEnv(DockingVectorEnv(num_envs=4, campaign_seed=0,
                                                       config=KWARGS["config"])))
    model = PPO("MlpPolicy", env, n_steps=64, batch_size=64, n_epochs=2, seed=0, device="cpu")
    model.set_logger(Logger(folder=None, output_formats=[]))  # (SB3's own: a folder in /tmp)
    before = [p.detach().clone() for p in model.policy.parameters()]
    model.learn(total_timesteps=256)
    assert model.num_timesteps == 256
    assert any(not torch.equal(a, b) for a, b in zip(before, model.policy.parameters(),
                                                     strict=True))
    assert np.isfinite(model.logger.name_to_value["train/value_loss"])
    action, _ = model.predict(env.reset(), deterministic=True)
    assert action.shape == (4, 3) and np.all(np.abs(action) <= 1.0)


@pytest.mark.parametrize("backend", ["native"])
def test_ppo_example_quick_mode_trains_and_evaluates(backend, tmp_path, monkeypatch):
    """examples/ppo_sb3.py in quick mode through the adapter (its make_vec_env route is SB3's
    own vector env over DockingEnv, which test_sub_environments_are_make_vec_envs_single_
    environments already flies; left out of the suite for its 30 s). Its environments fly the
    short timing, through the example's ENV_KWARGS. Without ``--tensorboard`` it leaves nothing
    in the temporary directory (SB3's own logger makes an empty folder there)."""
    import importlib.util
    import tempfile
    from pathlib import Path

    path = Path(__file__).resolve().parents[2] / "examples" / "ppo_sb3.py"
    spec = importlib.util.spec_from_file_location("ppo_sb3", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    mod.ENV_KWARGS["config"] = KWARGS["config"]
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    result = mod.main(["--quick", "--backend", backend])
    assert not list(tmp_path.iterdir())
    assert result["env_steps"] == 256 and result["env_steps_per_s"] > 0
    for key in ("baseline_lqg", "ppo_policy"):
        r = result[key]
        assert r["trials"] == 4
        assert r["docked_rate"] + r["missed_rate"] + r["aborted_rate"] == pytest.approx(1.0)
