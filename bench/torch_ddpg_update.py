#!/usr/bin/python3
"""The peer of pnp-bench-update: the same DDPG+HER update in PyTorch on the CPU.

Actor [31 -> 256 -> 256 -> 256 -> 4, tanh] and critic [35 -> 256 x 3 -> 1] (the
project's inputs: 25 observation + 3 goal values, 4 actions), batch 256, Adam 1e-3,
target clamp to [-1/(1-gamma), 0], action L2 1.0, Polyak 0.95 after every update, as in
pnp-bench-update. Prints one JSON object: updates per second at each thread setting and
the best. Run by pnp-bench-update with Debian's python3-torch (OpenBLAS).

Thread settings: PyTorch's own threads (torch.set_num_threads) and OpenBLAS's, which
Debian's build uses for its matrix products and which PyTorch does not set; OpenBLAS reads
its count once, at load, so each OpenBLAS setting runs in a child process.
"""
import json
import os
import subprocess
import sys
import time

TORCH_THREADS = (1, 2)
OPENBLAS_THREADS = (1, 2)

OBS, GOAL, ACT, BATCH, HIDDEN = 25, 3, 4, 256, 256
GAMMA, POLYAK, L2 = 0.98, 0.95, 1.0


def mlp(inputs, outputs, tanh):
    from torch import nn

    layers = [nn.Linear(inputs, HIDDEN), nn.ReLU(), nn.Linear(HIDDEN, HIDDEN), nn.ReLU(),
              nn.Linear(HIDDEN, HIDDEN), nn.ReLU(), nn.Linear(HIDDEN, outputs)]
    if tanh:
        layers.append(nn.Tanh())
    return nn.Sequential(*layers)


def run(updates, threads):
    import torch
    torch.set_num_threads(threads)
    torch.manual_seed(1)
    actor, critic = mlp(OBS + GOAL, ACT, True), mlp(OBS + GOAL + ACT, 1, False)
    actor_t, critic_t = mlp(OBS + GOAL, ACT, True), mlp(OBS + GOAL + ACT, 1, False)
    actor_t.load_state_dict(actor.state_dict())
    critic_t.load_state_dict(critic.state_dict())
    actor_opt = torch.optim.Adam(actor.parameters(), lr=1e-3)
    critic_opt = torch.optim.Adam(critic.parameters(), lr=1e-3)
    s = torch.rand(BATCH, OBS + GOAL) * 2 - 1
    s2 = torch.rand(BATCH, OBS + GOAL) * 2 - 1
    a = torch.rand(BATCH, ACT) * 2 - 1
    r = -torch.rand(BATCH, 1) * 0.5
    done = torch.zeros(BATCH, 1)

    def update():
        with torch.no_grad():
            q_next = critic_t(torch.cat([s2, actor_t(s2)], 1))
            y = torch.clamp(r + GAMMA * (1 - done) * q_next, -1 / (1 - GAMMA), 0)
        # Both losses with the critic's current parameters, then both steps (as the
        # original code and pnp's update do); autograd.grad computes only the gradients
        # asked for, so the actor's loss back-propagates through the critic's inputs only.
        critic_loss = ((critic(torch.cat([s, a], 1)) - y) ** 2).mean()
        pi = actor(s)
        actor_loss = -critic(torch.cat([s, pi], 1)).mean() + L2 * (pi[:, :3] ** 2).mean()
        critic_grads = torch.autograd.grad(critic_loss, list(critic.parameters()))
        actor_grads = torch.autograd.grad(actor_loss, list(actor.parameters()))
        for p, g in zip(critic.parameters(), critic_grads):
            p.grad = g
        for p, g in zip(actor.parameters(), actor_grads):
            p.grad = g
        critic_opt.step()
        actor_opt.step()
        with torch.no_grad():
            for net, target in ((actor, actor_t), (critic, critic_t)):
                for p, pt in zip(net.parameters(), target.parameters()):
                    pt.mul_(POLYAK).add_(p, alpha=1 - POLYAK)

    for _ in range(20):
        update()
    start = time.perf_counter()
    for _ in range(updates):
        update()
    return updates / (time.perf_counter() - start)


def child(updates):
    """Runs every PyTorch thread setting under this process's OpenBLAS setting."""
    import torch
    print(json.dumps({"torch_version": torch.__version__,
                      "by_torch_threads": {str(t): run(updates, t) for t in TORCH_THREADS}}))


def main():
    updates = int(sys.argv[1]) if len(sys.argv) > 1 else 200
    if len(sys.argv) > 2 and sys.argv[2] == "--child":
        child(updates)
        return
    by_setting, version = {}, None
    for blas in OPENBLAS_THREADS:
        env = dict(os.environ, OPENBLAS_NUM_THREADS=str(blas))
        out = subprocess.run([sys.executable, __file__, str(updates), "--child"], env=env,
                             check=True, capture_output=True, text=True).stdout
        result = json.loads(out.strip().splitlines()[-1])
        version = result["torch_version"]
        for threads, ups in result["by_torch_threads"].items():
            by_setting[f"torch_threads={threads},openblas_threads={blas}"] = ups
    best = max(by_setting, key=by_setting.get)
    print(json.dumps({"torch_version": version, "updates_per_s_by_setting": by_setting,
                      "best_setting": best, "updates_per_s": by_setting[best]}))


if __name__ == "__main__":
    main()
