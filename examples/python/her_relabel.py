#!/usr/bin/env python3
"""Hindsight relabelling with the environment's compute_reward, as HER's "future"
strategy does it: collect episodes (here with a noisy push towards the object, so that
the object moves), store their transitions, and relabel a sample of them with goals the
object actually reached later in the same episode. compute_reward is vectorised and runs
locally, so relabelling a whole batch costs no round-trip.

Prints how many stored transitions carry a non-failing (0) sparse reward before and after
relabelling: the signal HER creates from failed episodes.

  PYTHONPATH=build/python python3 examples/python/her_relabel.py --episodes 20
"""

from __future__ import annotations

import argparse
import sys

import pnp  # first: it finds Debian's numpy and grpcio for any CPython of their version

import numpy as np  # noqa: E402


def collect(env: pnp.PickAndPlaceEnv, episodes: int, rng: np.random.Generator) -> dict:
    """Whole episodes of 50 steps as arrays: achieved goals (E, T + 1, 3), desired goals
    (E, T, 3), rewards (E, T). An episode the simulator cut short with a physics fault (its
    state is then the next episode's) is left out and counted."""
    achieved, desired, rewards, faults = [], [], [], 0
    while len(rewards) < episodes:
        obs, _ = env.reset()
        ag, dg, r = [obs["achieved_goal"]], [], []
        truncated = terminated = False
        while not (terminated or truncated):
            # Towards the object with noise: the gripper bumps it, so it moves.
            towards = np.clip(obs["observation"][6:9] / 0.05, -1, 1)
            action = np.append(towards + rng.normal(0, 0.5, 3), rng.uniform(-1, 1))
            dg.append(obs["desired_goal"])
            obs, reward, terminated, truncated, info = env.step(np.clip(action, -1, 1))
            ag.append(obs["achieved_goal"])
            r.append(reward)
        if info["physics_fault"]:
            faults += 1
            continue
        achieved.append(ag)
        desired.append(dg)
        rewards.append(r)
    return {"achieved": np.array(achieved), "desired": np.array(desired),
            "rewards": np.array(rewards), "faults": faults}


def relabel(env, episodes: dict, batch: int, future_p: float, rng: np.random.Generator):
    """A batch of transitions, a fraction `future_p` of them with the goal replaced by an
    achieved goal from later in the episode, and their rewards recomputed."""
    n_episodes, horizon = episodes["rewards"].shape
    e = rng.integers(n_episodes, size=batch)
    t = rng.integers(horizon, size=batch)
    goals = episodes["desired"][e, t].copy()
    her = rng.random(batch) < future_p
    future = t + 1 + (rng.random(batch) * (horizon - t)).astype(int)
    goals[her] = episodes["achieved"][e[her], future[her]]
    rewards = env.compute_reward(episodes["achieved"][e, t + 1], goals, None)
    return goals, rewards


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=20)
    parser.add_argument("--batch", type=int, default=4096)
    parser.add_argument("--future-p", type=float, default=0.8, help="HER's relabelled fraction")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--robot", default="fetch")
    parser.add_argument("--object", default="block")
    parser.add_argument("--world", default="gym")
    parser.add_argument("--sim", help="simulation service host:port (default: as pnpctl)")
    args = parser.parse_args()
    if args.episodes <= 0:
        parser.error(f"--episodes: expected a positive integer, got {args.episodes}")
    if not 0 <= args.future_p <= 1:
        parser.error(f"--future-p: expected a fraction in [0, 1], got {args.future_p}")

    rng = np.random.default_rng(args.seed)
    with pnp.PickAndPlaceEnv(args.sim, robot=args.robot, object=args.object, world=args.world,
                             seed=args.seed) as env:
        episodes = collect(env, args.episodes, rng)
        # The stored rewards are compute_reward's on the stored goals: a check of the API.
        stored = env.compute_reward(episodes["achieved"][:, 1:], episodes["desired"], None)
        assert np.array_equal(stored, episodes["rewards"]), "step's reward != compute_reward's"
        _, relabelled = relabel(env, episodes, args.batch, args.future_p, rng)
    before = float(np.mean(episodes["rewards"] == 0))
    after = float(np.mean(relabelled == 0))
    print(f"{args.world}/{args.robot}/{args.object}, {args.episodes} episodes "
          f"({episodes['faults']} cut short by a physics fault, "
          f"left out): {before:.3f} of stored transitions reach their goal; "
          f"after relabelling {args.future_p:.0%} of a batch of {args.batch} with future "
          f"achieved goals: {after:.3f}")


if __name__ == "__main__":
    try:
        main()
    except pnp.PlatformError as e:
        sys.exit(f"her_relabel: {e}")
