"""PickAndPlaceEnv and VectorPickAndPlaceEnv against a real simulation service."""

import grpc
import numpy as np
import pytest

import pnp
from pnp.sim_client import SimClient

ZERO = np.zeros(4)


def run_episode(env, actions):
    """Observations of one episode under the given actions (until it ends)."""
    obs, _ = env.reset()
    trajectory = [obs]
    for a in actions:
        obs, _, terminated, truncated, _ = env.step(a)
        trajectory.append(obs)
        if terminated or truncated:
            break
    return trajectory


@pytest.fixture
def env(sim_server):
    with pnp.PickAndPlaceEnv(sim_server.address, robot="panda", seed=7) as e:
        yield e


def test_reset_gives_the_goal_observation_dict(env):
    obs, info = env.reset()
    assert set(obs) == {"observation", "achieved_goal", "desired_goal"}
    assert obs["observation"].shape == (25,) and obs["observation"].dtype == np.float64
    assert obs["achieved_goal"].shape == (3,) and obs["achieved_goal"].dtype == np.float64
    assert obs["desired_goal"].shape == (3,) and obs["desired_goal"].dtype == np.float64
    # The achieved goal is the object's position (docs/OBSERVATION.md, indices 3-5).
    np.testing.assert_array_equal(obs["achieved_goal"], obs["observation"][3:6])
    assert info == {"elapsed_steps": 0}


def test_an_episode_is_50_steps_truncated_never_terminated(env):
    env.reset()
    for t in range(1, 51):
        obs, reward, terminated, truncated, info = env.step(ZERO)
        assert isinstance(reward, float) and reward in (0.0, -1.0)
        assert terminated is False
        assert truncated is (t == 50)
        assert info["elapsed_steps"] == t
        assert info["is_success"] in (0.0, 1.0)
        assert info["physics_fault"] is None


def test_the_same_seed_gives_the_same_episodes(sim_server):
    rng = np.random.default_rng(0)
    actions = rng.uniform(-1, 1, (20, 4))
    with pnp.PickAndPlaceEnv(sim_server.address, seed=11) as a, \
            pnp.PickAndPlaceEnv(sim_server.address, seed=11) as b, \
            pnp.PickAndPlaceEnv(sim_server.address, seed=12) as c:
        for first, second in zip(run_episode(a, actions), run_episode(b, actions)):
            for key in first:
                np.testing.assert_array_equal(first[key], second[key])
        assert not np.array_equal(a.reset()[0]["desired_goal"], c.reset()[0]["desired_goal"])


def test_reset_with_a_seed_starts_that_seeds_episodes_over(sim_server):
    with pnp.PickAndPlaceEnv(sim_server.address, seed=0) as a, \
            pnp.PickAndPlaceEnv(sim_server.address, seed=5) as b:
        a.reset()
        first, _ = a.reset(seed=5)
        second, _ = a.reset()
        np.testing.assert_array_equal(first["desired_goal"], b.reset()[0]["desired_goal"])
        np.testing.assert_array_equal(second["desired_goal"], b.reset()[0]["desired_goal"])
        assert not np.array_equal(first["desired_goal"], second["desired_goal"])


def test_compute_reward_equals_the_services_and_is_vectorised(sim_server):
    rng = np.random.default_rng(1)
    achieved = rng.uniform(0, 1, (64, 3))
    goals = achieved + rng.normal(0, 0.05, (64, 3))
    client = SimClient(pnp.Endpoints(sim=sim_server.address))
    try:
        service = client.compute_reward(achieved, goals)
    finally:
        client.close()
    with pnp.PickAndPlaceEnv(sim_server.address, reward_type="dense") as dense, \
            pnp.PickAndPlaceEnv(sim_server.address) as sparse:
        np.testing.assert_allclose(dense.compute_reward(achieved, goals, None), service,
                                   rtol=0, atol=1e-12)
        expected_sparse = np.where(-service >= dense.success_distance_m, -1.0, 0.0)
        np.testing.assert_array_equal(sparse.compute_reward(achieved, goals, {}), expected_sparse)
        assert sparse.compute_reward(achieved.reshape(8, 8, 3), goals.reshape(8, 8, 3),
                                     None).shape == (8, 8)
        assert 0 < np.count_nonzero(expected_sparse) < 64  # both outcomes were compared


def test_the_steps_reward_is_compute_rewards_and_success_agrees(sim_server):
    with pnp.PickAndPlaceEnv(sim_server.address, reward_type="dense", seed=3) as env:
        env.reset()
        for _ in range(5):
            obs, reward, _, _, info = env.step([0.3, -0.2, -0.5, 1.0])
            assert reward == pytest.approx(
                -np.linalg.norm(obs["achieved_goal"] - obs["desired_goal"]), abs=1e-12)
            assert info["is_success"] == float(-reward < env.success_distance_m)


def test_a_non_finite_action_raises_with_the_services_message(env):
    env.reset()
    with pytest.raises(pnp.PlatformError) as e:
        env.step([np.nan, 0, 0, 0])
    assert e.value.code == grpc.StatusCode.INVALID_ARGUMENT
    assert "actions[0].action" in e.value.details and "finite" in e.value.details
    env.step(ZERO)  # nothing was lost: the episode goes on


def test_an_action_of_the_wrong_length_is_refused_before_any_call(env):
    env.reset()
    with pytest.raises(ValueError, match=r"action: expected shape \(4,\)"):
        env.step([0.0, 0.0, 0.0])


def test_stepping_a_finished_episode_raises_failed_precondition(env):
    env.reset()
    for _ in range(50):
        env.step(ZERO)
    with pytest.raises(pnp.PlatformError) as e:
        env.step(ZERO)
    assert e.value.code == grpc.StatusCode.FAILED_PRECONDITION
    assert "Reset it first" in e.value.details


@pytest.mark.parametrize("field,kwargs", [
    ("robot", {"robot": "ur5"}), ("object", {"object": "sphere"}), ("world", {"world": "mars"}),
    ("reward_type", {"reward_type": "shaped"}), ("seed", {"seed": -1}),
])
def test_bad_arguments_name_the_field(sim_server, field, kwargs):
    with pytest.raises(ValueError, match=f"^{field}: expected"):
        pnp.PickAndPlaceEnv(sim_server.address, **kwargs)


def test_close_releases_the_services_environment(sim_server):
    env = pnp.PickAndPlaceEnv(sim_server.address)
    env.reset()
    env_id = env._batch.env_id()
    env.close()
    client = SimClient(pnp.Endpoints(sim=sim_server.address))
    try:
        with pytest.raises(pnp.PlatformError) as e:
            client.reset(env_id, 1)
        assert e.value.code == grpc.StatusCode.NOT_FOUND
    finally:
        client.close()
    with pytest.raises(RuntimeError, match="closed"):
        env.reset()


def test_a_vector_envs_first_environment_plays_the_single_envs_episodes(sim_server):
    rng = np.random.default_rng(2)
    actions = rng.uniform(-1, 1, (10, 3, 4))
    with pnp.VectorPickAndPlaceEnv(3, sim_server.address, seed=21) as vec, \
            pnp.PickAndPlaceEnv(sim_server.address, seed=21) as single:
        obs, _ = vec.reset()
        one, _ = single.reset()
        assert obs["observation"].shape == (3, 25) and obs["desired_goal"].shape == (3, 3)
        for a in actions:
            obs, rewards, terminated, truncated, info = vec.step(a)
            one, reward, *_ = single.step(a[0])
            np.testing.assert_array_equal(obs["observation"][0], one["observation"])
            assert rewards.shape == (3,) and rewards[0] == reward
            assert terminated.shape == truncated.shape == info["is_success"].shape == (3,)
        # The environments of a batch play different episodes.
        assert not np.array_equal(obs["desired_goal"][0], obs["desired_goal"][1])


def test_a_vector_env_resets_finished_episodes_itself(sim_server):
    with pnp.VectorPickAndPlaceEnv(2, sim_server.address, seed=4) as vec, \
            pnp.PickAndPlaceEnv(sim_server.address, seed=4) as single:
        vec.reset()
        single.reset()
        for _ in range(49):
            obs, _, _, truncated, info = vec.step(np.zeros((2, 4)))
            single.step(ZERO)
            assert not truncated.any() and "final_observation" not in info
        obs, _, _, truncated, info = vec.step(np.zeros((2, 4)))
        last, *_ = single.step(ZERO)
        assert truncated.all() and info["_final_observation"].all() and info["_final_info"].all()
        assert info["final_info"][0]["elapsed_steps"] == 50
        np.testing.assert_array_equal(info["elapsed_steps"], 0)  # of the new episodes
        np.testing.assert_array_equal(info["final_observation"][0]["observation"],
                                      last["observation"])
        following, _ = single.reset()  # episode 1 of environment 0
        np.testing.assert_array_equal(obs["observation"][0], following["observation"])
        vec.step(np.zeros((2, 4)))  # the new episodes run


def test_a_vector_env_refuses_actions_of_the_wrong_shape(sim_server):
    with pnp.VectorPickAndPlaceEnv(2, sim_server.address) as vec:
        vec.reset()
        with pytest.raises(ValueError, match=r"action: expected shape \(2, 4\)"):
            vec.step(np.zeros(4))
    with pytest.raises(ValueError, match="num_envs: expected an integer from 1 to 64"):
        pnp.VectorPickAndPlaceEnv(65, sim_server.address)


def test_an_environment_the_service_dropped_is_replaced_at_the_next_reset(sim_server):
    # As after an idle timeout: the service no longer knows the batch.
    env = pnp.PickAndPlaceEnv(sim_server.address, seed=8)
    first, _ = env.reset()
    client = SimClient(pnp.Endpoints(sim=sim_server.address))
    try:
        client.close_env(env._batch.env_id())
    finally:
        client.close()
    with pytest.raises(pnp.PlatformError) as e:
        env.step(ZERO)
    assert e.value.code == grpc.StatusCode.NOT_FOUND
    again, _ = env.reset()  # a new batch: the seed's episodes from the first
    np.testing.assert_array_equal(again["desired_goal"], first["desired_goal"])
    env.close()  # nothing left to release, and no error


def test_the_arm_actuated_panda_lags_the_mocap_hand_on_the_same_episode(sim_server):
    """actuation="arm": the Panda's hand moved by its controller (docs/SIMULATION.md),
    the same episode (object, goal) as the mocap world's for the seed, the hand slower."""
    up = np.array([0.0, 0.0, 1.0, 0.0])
    rises = {}
    for actuation, episode_steps in (("mocap", 50), ("arm", 75)):
        with pnp.PickAndPlaceEnv(sim_server.address, robot="panda", seed=7,
                                 actuation=actuation) as e:
            assert e.max_episode_steps == episode_steps  # the arm's episode is longer
            obs, _ = e.reset()
            start = obs["observation"][2]
            after, _, _, _, _ = e.step(up)
            rises[actuation] = after["observation"][2] - start
            goals = obs["desired_goal"]
        rises[actuation + "_goal"] = goals
    np.testing.assert_allclose(rises["mocap_goal"], rises["arm_goal"], atol=1e-9)
    assert 0 < rises["arm"] < 0.5 * rises["mocap"]


def test_an_arm_actuated_fetch_is_refused_naming_actuation(sim_server):
    with pytest.raises(pnp.PlatformError) as e:
        with pnp.PickAndPlaceEnv(sim_server.address, robot="fetch", actuation="arm") as env:
            env.reset()
    assert e.value.code == grpc.StatusCode.INVALID_ARGUMENT
    assert "actuation" in e.value.details
    with pytest.raises(ValueError, match="actuation: expected one of default, mocap, arm"):
        pnp.PickAndPlaceEnv(sim_server.address, robot="panda", actuation="teleport")


def test_a_reply_of_the_wrong_shape_is_refused_before_use():
    from pnp.sim.v1 import sim_service_pb2 as sim
    from pnp.sim_client import checked_count, observation_dict
    state = sim.EnvState()
    state.observation.values.extend([0.0] * 24)
    with pytest.raises(pnp.ReplyError, match="reply observation values: expected 25, got 24"):
        observation_dict(state)
    state.observation.values.append(0.0)
    assert observation_dict(state)["observation"].shape == (25,)
    with pytest.raises(pnp.ReplyError, match="Step reply results: expected 2, got 1"):
        checked_count([object()], 2, "Step reply results")
