"""pnp.Platform against real training and inference services over one store."""

import json
import os
import pathlib
import subprocess
import sys

import grpc
import numpy as np
import pytest

import pnp
from conftest import BIN_DIR, SOURCE_DIR

HELD_OUT_SEED = 424242


@pytest.fixture(scope="module")
def platform(sim_server, inference_server, approach_server):
    with pnp.Platform({"sim": sim_server.address, "inference": inference_server.address,
                       "approach": approach_server.address}) as p:
        yield p


def test_serving_status_names_the_served_hierarchy(platform):
    status = platform.serving_status()
    assert status["ready"]
    roles = {r["role"]: r for r in status["roles"]}
    assert set(roles) == {"approach", "manipulate", "retract", "hlc"}
    assert all(r["robot"] == "panda" and r["object"] == "block" for r in roles.values())


def test_a_session_answers_each_step(platform, sim_server):
    with pnp.PickAndPlaceEnv(sim_server.address, robot="panda", world="paper") as env, \
            platform.session() as session:
        obs, _ = env.reset()
        first = session.act(obs["observation"], obs["desired_goal"])
        assert first.action.shape == (4,) and np.all(np.abs(first.action) <= 1)
        assert first.subtask == "approach" and first.decided and first.step == 1
        assert first.subtask_probabilities.shape == (3,)
        assert np.isfinite(first.value) and first.choreographer_checkpoint_id > 0
        obs, *_ = env.step(first.action)
        assert session.act(obs["observation"], obs["desired_goal"]).step == 2


def test_a_session_declares_its_episode_length(platform, sim_server):
    with pnp.PickAndPlaceEnv(sim_server.address, robot="panda", world="paper",
                             actuation="arm") as env, \
            platform.session(episode_steps=env.max_episode_steps) as session:
        obs, _ = env.reset()
        assert session.act(obs["observation"], obs["desired_goal"]).step == 1
    for bad in (-1, 10001, 7.5, True):
        with pytest.raises(ValueError, match="episode_steps: expected 0"):
            platform.session(episode_steps=bad)


def test_a_session_passes_on_the_servers_refusal(platform):
    with platform.session() as session:
        with pytest.raises(ValueError, match="observation: expected 25 values"):
            session.act(np.zeros(24), np.zeros(3))
        observation = np.zeros(25)
        observation[4] = np.inf
        with pytest.raises(pnp.PlatformError) as e:
            session.act(observation, np.zeros(3))
    assert e.value.code == grpc.StatusCode.INVALID_ARGUMENT
    assert "observation" in e.value.details
    with pytest.raises(RuntimeError, match="closed"):  # the stream ended with the refusal
        session.act(np.zeros(25), np.zeros(3))


def test_the_example_plays_the_same_episodes_as_pnpctl_evaluate(sim_server, inference_server):
    env = dict(os.environ, PNP_SIM_ADDRESS=sim_server.address,
               PNP_INFERENCE_ADDRESS=inference_server.address)
    example = subprocess.run(
        [sys.executable, str(SOURCE_DIR / "examples" / "python" / "evaluate_served.py"),
         "--episodes", "20", "--json", "--run-dir", "/nonexistent"],
        env=env, capture_output=True, text=True, timeout=300, check=True)
    ours = json.loads(example.stdout)
    assert (ours["robot"], ours["object"], ours["world"], ours["actuation"]) == (
        "panda", "block", "paper", "mocap")
    reference = subprocess.run(
        [str(BIN_DIR / "pnpctl"), "--sim", sim_server.address, "--inference",
         inference_server.address, "evaluate", "--robot", "panda", "--object", "block",
         "--world", "paper", "--actuation", "mocap", "--episodes", "20", "--seed",
         str(HELD_OUT_SEED), "--json"],
        capture_output=True, text=True, timeout=300, check=True)
    theirs = json.loads(reference.stdout)
    for key in ("episodes", "successes", "env_steps", "seed", "sequences"):
        assert ours[key] == theirs[key], key
    assert ours["successes"] > 0


def test_a_training_run_from_start_to_its_metrics_and_checkpoints(platform):
    run = platform.train("approach", robot="fetch", seed=2, max_steps=400,
                         eval_interval_steps=200, eval_episodes=4, ddpg={"hidden": [16, 16]})
    assert run.role == "approach" and run.run_id > 0
    progress = list(run.watch())
    assert progress[-1]["run"]["state"] == "succeeded"
    assert [p["metric"]["env_steps"] for p in progress if p["metric"]][-1] == 400
    final = run.wait()  # returns at once: the run has finished
    assert final["state"] == "succeeded" and final["env_steps"] == 400
    metrics = run.metrics()
    rows = metrics.to_dict("records") if hasattr(metrics, "to_dict") else metrics
    assert [row["env_steps"] for row in rows] == [200, 400]
    checkpoints = run.checkpoints()
    assert checkpoints and all(c["run_id"] == run.run_id for c in checkpoints)
    assert run.run_id in [r["run_id"] for r in platform.runs()]
    assert platform.run(run.run_id).role == "approach"
    assert any(c["run_id"] == run.run_id for c in platform.checkpoints())


def test_runs_gathers_every_roles_service_newest_first(approach_server, retract_server):
    # Each training service lists its own role's runs: runs() asks each (a service that
    # is down is skipped) and merges them. The store holds the imported hierarchy.
    nowhere = "127.0.0.1:1"
    with pnp.Platform({"approach": approach_server.address, "retract": retract_server.address,
                       "manipulate": nowhere, "hlc": nowhere, "e2e": nowhere}) as p:
        every = p.runs()
        assert {"approach", "retract"} <= {r["role"] for r in every}
        ids = [r["run_id"] for r in every]
        assert ids == sorted(ids, reverse=True)
        assert {r["role"] for r in p.runs(role="retract")} == {"retract"}
    roles = ("approach", "manipulate", "retract", "hlc", "e2e")
    with pnp.Platform({role: nowhere for role in roles}) as p:
        with pytest.raises(pnp.PlatformError) as refused:
            p.runs()
        assert refused.value.code == grpc.StatusCode.UNAVAILABLE


def test_bad_training_requests_name_the_field(platform):
    with pytest.raises(ValueError, match=r"^ddpg\.learning_rate: not a setting"):
        platform.train("approach", ddpg={"learning_rate": 0.1})
    with pytest.raises(ValueError, match="^role: expected one of"):
        platform.train("grasp")
    with pytest.raises(pnp.PlatformError) as e:
        platform.train("approach", max_steps=-5)
    assert e.value.code == grpc.StatusCode.INVALID_ARGUMENT
    assert "max_steps" in e.value.details


def test_promoting_an_unknown_checkpoint_is_not_found(platform):
    with pytest.raises(pnp.PlatformError) as e:
        platform.promote(999999)
    assert e.value.code == grpc.StatusCode.NOT_FOUND
    assert platform.serving_status()["ready"]  # nothing was lost


def test_endpoints_refuse_unknown_names_and_a_token_without_tls(tmp_path):
    with pytest.raises(ValueError, match="unknown service or setting 'simulator'"):
        pnp.Platform({"simulator": "127.0.0.1:1"})
    token = tmp_path / "token"
    token.write_text("secret\n")
    with pytest.raises(ValueError, match="^tls_ca: expected a CA file"):
        pnp.Endpoints(token_file=str(token)).channel("127.0.0.1:1")
    path = tmp_path / "endpoints.json"
    path.write_text(json.dumps({"sim": "127.0.0.1:7", "inference": "127.0.0.1:8"}))
    found = pnp.Endpoints.discover(str(tmp_path))
    assert (found.sim, found.inference, found.hlc) == ("127.0.0.1:7", "127.0.0.1:8",
                                                      "127.0.0.1:50055")


def test_a_stale_endpoints_file_is_named_when_its_platform_does_not_answer(tmp_path, monkeypatch):
    """The file scripts/run left behind (or PNP_ENDPOINTS names, as pnpctl reads it): a
    service there that does not answer is reported with the file its address came from."""
    path = tmp_path / "stale.json"
    path.write_text(json.dumps({"approach": "127.0.0.1:1", "inference": "127.0.0.1:1"}))
    monkeypatch.setenv("PNP_ENDPOINTS", str(path))
    for name in ("PNP_APPROACH_ADDRESS", "PNP_INFERENCE_ADDRESS"):
        monkeypatch.delenv(name, raising=False)
    with pnp.Platform(timeout_s=2) as p:
        with pytest.raises(pnp.PlatformError) as failed:
            p.serving_status()
    assert failed.value.code == grpc.StatusCode.UNAVAILABLE
    assert f"the addresses came from {path}" in str(failed.value)
    monkeypatch.setenv("PNP_ENDPOINTS", str(tmp_path / "missing.json"))
    with pytest.raises(ValueError, match="^PNP_ENDPOINTS: cannot read"):
        pnp.Endpoints.discover()


def test_inference_replicas_are_one_target_and_a_killed_one_costs_no_error(
        workdir, store_with_hierarchy):
    """Two inference servers named by one target (as dns:///pnp-inference:50060 names a
    Deployment's Pods): calls are balanced over both and retried on the survivor when one is
    SIGKILLed; none fails."""
    from conftest import Server
    replicas = [Server(f"inference-replica-{k}",
                       ["pnp-inference-server", "--db", str(store_with_hierarchy)], workdir)
                for k in (1, 2)]
    target = "ipv4:" + ",".join(r.address for r in replicas)
    try:
        with pnp.Platform({"inference": target}) as p:
            for k in range(60):
                if k == 20:
                    replicas[0].process.kill()
                assert p.serving_status()["ready"]
    finally:
        for r in replicas:
            r.stop()
