#!/usr/bin/env python3
"""A random agent on the simulation service through pnp.PickAndPlaceEnv: the smallest
complete use of the Gymnasium-style API (reset, step, spaces, info["is_success"]).

  PYTHONPATH=build/python python3 examples/python/random_agent.py --episodes 10
"""

from __future__ import annotations

import argparse
import sys

import pnp  # first: it finds Debian's numpy and grpcio for any CPython of their version

import numpy as np  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=10)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--robot", default="fetch")
    parser.add_argument("--object", default="block")
    parser.add_argument("--world", default="gym")
    parser.add_argument("--sim", help="simulation service host:port (default: as pnpctl)")
    args = parser.parse_args()
    if args.episodes <= 0:
        parser.error(f"--episodes: expected a positive integer, got {args.episodes}")

    with pnp.PickAndPlaceEnv(args.sim, robot=args.robot, object=args.object, world=args.world,
                             seed=args.seed) as env:
        env.action_space.seed(args.seed)
        successes, final_distances = 0, []
        for _ in range(args.episodes):
            obs, _ = env.reset()
            truncated = terminated = False
            while not (terminated or truncated):
                obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
            successes += int(info["is_success"])
            final_distances.append(np.linalg.norm(obs["achieved_goal"] - obs["desired_goal"]))
    print(f"random agent, {args.world}/{args.robot}/{args.object}: success "
          f"{successes / args.episodes:.3f} over {args.episodes} episodes (seed {args.seed}), "
          f"mean final distance {np.mean(final_distances):.3f} m")


if __name__ == "__main__":
    try:
        main()
    except pnp.PlatformError as e:
        sys.exit(f"random_agent: {e}")
