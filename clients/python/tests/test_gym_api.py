"""Gymnasium API conformance of PickAndPlaceEnv, written here (gymnasium itself is not a
Debian 12 package; where it is installed, its own env checker runs too)."""

import inspect

import numpy as np
import pytest

import pnp


@pytest.fixture
def env(sim_server):
    with pnp.PickAndPlaceEnv(sim_server.address, seed=3) as e:
        yield e


def test_reset_and_step_have_gymnasiums_signatures():
    reset = inspect.signature(pnp.PickAndPlaceEnv.reset).parameters
    assert reset["seed"].kind == inspect.Parameter.KEYWORD_ONLY and reset["seed"].default is None
    assert reset["options"].kind == inspect.Parameter.KEYWORD_ONLY
    assert list(inspect.signature(pnp.PickAndPlaceEnv.step).parameters) == ["self", "action"]
    assert list(inspect.signature(pnp.PickAndPlaceEnv.compute_reward).parameters) == [
        "self", "achieved_goal", "desired_goal", "info"]


def test_the_spaces_contain_what_the_env_returns(env):
    obs, info = env.reset()
    assert isinstance(info, dict)
    assert env.observation_space.contains(obs)
    assert env.action_space.shape == (4,) and env.action_space.dtype == np.float32
    np.testing.assert_array_equal(env.action_space.low, -1)
    np.testing.assert_array_equal(env.action_space.high, 1)
    for key, size in (("observation", 25), ("achieved_goal", 3), ("desired_goal", 3)):
        assert env.observation_space[key].shape == (size,)
    for _ in range(10):
        action = env.action_space.sample()
        assert env.action_space.contains(action)
        obs, reward, terminated, truncated, info = env.step(action)
        assert env.observation_space.contains(obs)
        assert isinstance(reward, float) and isinstance(info, dict)
        assert isinstance(terminated, bool) and isinstance(truncated, bool)
    assert not env.action_space.contains(np.full(4, 2, dtype=np.float32))


def test_seeding_makes_everything_reproducible(sim_server):
    def rollout(seed):
        with pnp.PickAndPlaceEnv(sim_server.address) as e:
            obs, _ = e.reset(seed=seed)  # seeds the episodes and the action space
            out = [obs["observation"]]
            for _ in range(15):
                obs, *_ = e.step(e.action_space.sample())
                out.append(obs["observation"])
            return np.array(out)

    np.testing.assert_array_equal(rollout(9), rollout(9))
    assert not np.array_equal(rollout(9), rollout(10))


def test_compute_reward_takes_batches_of_any_shape(env):
    for batch in [(), (1,), (7,), (2, 5)]:
        achieved = np.zeros(batch + (3,))
        goals = np.full(batch + (3,), 0.1)
        r = env.compute_reward(achieved, goals, None)
        assert r.shape == batch
        np.testing.assert_array_equal(r, -1.0)
    with pytest.raises(ValueError, match="same shape ending in 3"):
        env.compute_reward(np.zeros((4, 3)), np.zeros((4, 2)), None)


def test_the_success_flag_and_the_sparse_reward_agree(env):
    env.reset()
    for _ in range(20):  # every step: reward 0 exactly when info["is_success"] is 1
        _, reward, _, _, info = env.step(env.action_space.sample())
        assert (reward == 0.0) == (info["is_success"] == 1.0)
    goals = env.reset()[0]["desired_goal"]
    near = goals + [0.049, 0, 0]
    far = goals + [0.05, 0, 0]
    assert env.compute_reward(near, goals, None) == 0.0
    assert env.compute_reward(far, goals, None) == -1.0


def test_gymnasiums_checker_when_gymnasium_is_installed(sim_server):
    gymnasium = pytest.importorskip("gymnasium")
    from gymnasium.utils.env_checker import check_env
    env = gymnasium.make("pnp/PickAndPlace-v0", sim_address=sim_server.address)
    try:
        check_env(env.unwrapped, skip_render_check=True)
    finally:
        env.close()
