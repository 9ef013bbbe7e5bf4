#!/usr/bin/env python3
"""Plays held-out episodes of the hierarchy the inference service serves, through the
Gymnasium-style environment and a live inference session, and prints its success rate.

The episodes are the simulation service's episodes of --seed, the same ones
`pnpctl evaluate --seed` plays, so both print the same success rate and choice sequences.
Robot, object, world and actuation default to what the served choreographer was trained on.

  PYTHONPATH=build/python python3 examples/python/evaluate_served.py --episodes 100
"""

from __future__ import annotations

import argparse
import collections
import json
import sys

import pnp

HELD_OUT_SEED = 424242  # pnpctl evaluate's default: no training run uses it
LETTERS = {"approach": "A", "manipulate": "M", "retract": "R"}


def served_world(platform: pnp.Platform) -> dict:
    """robot, object, world and actuation of the served choreographer, where recorded."""
    status = platform.serving_status()
    if not status["ready"]:
        sys.exit("evaluate_served: the inference service serves no hierarchy yet "
                 "(promote one: pnpctl promote)")
    for role in status["roles"]:
        if role["role"] == "hlc":
            return {k: role[k] for k in ("robot", "object", "world", "actuation") if role[k]}
    return {}


def play(env: pnp.PickAndPlaceEnv, platform: pnp.Platform) -> tuple[bool, int, str]:
    """One episode: (success, steps, the subtasks the choreographer chose, as letters)."""
    obs, _ = env.reset()
    choices, steps = "", 0
    # The episode's length, declared: the hierarchy's subtask caps scale to it, as pnpctl's.
    with platform.session(episode_steps=env.max_episode_steps) as session:
        while True:
            p = session.act(obs["observation"], obs["desired_goal"])
            if p.decided and p.subtask:
                choices += LETTERS[p.subtask]
            obs, _, terminated, truncated, info = env.step(p.action)
            steps += 1
            if terminated or truncated:
                return bool(info["is_success"]), steps, choices


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--seed", type=int, default=HELD_OUT_SEED)
    parser.add_argument("--robot", help="default: the served hierarchy's")
    parser.add_argument("--object", help="default: the served hierarchy's")
    parser.add_argument("--world", help="default: the served hierarchy's")
    parser.add_argument("--actuation", help="mocap or arm; default: the served hierarchy's")
    parser.add_argument("--run-dir", default="runs/platform",
                        help="where scripts/run wrote endpoints.json (PNP_*_ADDRESS win)")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args()
    if args.episodes <= 0:
        parser.error(f"--episodes: expected a positive integer, got {args.episodes}")

    with pnp.Platform(pnp.Endpoints.discover(args.run_dir)) as platform:
        world = {"robot": "fetch", "object": "block", "world": "gym", "actuation": "default",
                 **served_world(platform)}
        for key in world:
            if getattr(args, key):
                world[key] = getattr(args, key)
        successes, env_steps = 0, 0
        sequences: collections.Counter = collections.Counter()
        with pnp.PickAndPlaceEnv(platform.endpoints, seed=args.seed, **world) as env:
            for _ in range(args.episodes):
                success, steps, choices = play(env, platform)
                successes += success
                env_steps += steps
                sequences[choices] += 1

    where = f"{world['world']}/{world['robot']}/{world['object']} ({world['actuation']} hand)"
    ranked = sorted(sequences.items(), key=lambda kv: (-kv[1], kv[0]))
    if args.json:
        print(json.dumps({"episodes": args.episodes, "successes": successes,
                          "success_rate": successes / args.episodes, "env_steps": env_steps,
                          "seed": args.seed, "sequences": ranked, **world}))
        return
    print(f"{where}: success {successes / args.episodes:.3f} over {args.episodes} held-out "
          f"episodes (seed {args.seed}), most frequent choices {ranked[0][0]} x{ranked[0][1]}")


if __name__ == "__main__":
    try:
        main()
    except pnp.PlatformError as e:
        sys.exit(f"evaluate_served: {e}")
