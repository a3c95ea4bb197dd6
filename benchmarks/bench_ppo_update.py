"""PPO update cost on this machine, against MuJoCo physics measured in the same run.

Run: ``.venv/bin/python benchmarks/bench_ppo_update.py [--batches 2048,8192,32768]
[--threads 1,2] [--e2e 128x64,256x32,512x16]``

1. Update: one PPO update (paper Table 3: 5 epochs, minibatches of 8192, actor [300,200,100],
   critic [400,400,300,200], tanh) on a rollout of the given size, with the observation sizes
   of the human character's default recipe, for 1 and 2 torch threads. Reported as fresh
   samples/s (rollout samples per second of update).
2. Physics: one control step of ``BatchedSim`` with the human character (default substeps,
   all cores), 256 worlds, as env steps/s. The ratio physics/update says how much of a
   training iteration the update takes per sample collected (ratio 1: as long as physics).
3. ``--e2e NxT,...``: whole training iterations (collection on 1 thread + update on 2) on the
   real environment for each env count N and rollout length T, median steps/s of iterations
   2.. (the first pays for warm-up), and its ratio to the raw physics rate measured above in
   the same run. This is how the defaults (256 envs x 32 steps) were chosen.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
import torch

from retarget.env.build import env_from_recipe
from retarget.learn import PPOConfig, PPOLearner, torch_threads
from retarget.recipe import load
from retarget.registry.loader import load_plugins


def human_env(num_envs: int):
    resolved = load(None, load_plugins(), shorthands={"character": "human"}, assignments=[])
    return env_from_recipe(resolved, num_envs=num_envs)


def fill_rollout(ppo: PPOLearner, g: torch.Generator) -> None:
    """Random but self-consistent rollout data (log-probs of the stored actions)."""
    st = ppo.storage
    for buf in st.obs.values():
        buf.normal_(generator=g)
    with torch.no_grad():
        mean = ppo.actor(st.obs[ppo.actor_key])
        st.actions.copy_(mean + 0.14 * torch.randn(mean.shape, generator=g))
        st.log_probs.copy_(ppo.actor.log_prob(mean, st.actions))
        st.values.normal_(generator=g)
    st.rewards.uniform_(generator=g)
    st.compute_returns(torch.zeros(st.num_envs), 0.97, 0.95)


def time_update(dims: dict[str, int], action_dim: int, samples: int, threads: int) -> float:
    """Median seconds of one full PPO update (3 repetitions after a warm-up)."""
    cfg = PPOConfig(rollout_steps=16, update_threads=threads)
    g = torch.Generator().manual_seed(0)
    ppo = PPOLearner(cfg, dims, action_dim, samples // 16, g)
    times = []
    with torch_threads(threads):
        for rep in range(4):
            fill_rollout(ppo, g)
            t = time.perf_counter()
            ppo.update()
            if rep:
                times.append(time.perf_counter() - t)
    return statistics.median(times)


def physics_steps_per_s(num_envs: int = 256, steps: int = 40) -> tuple[float, str]:
    from retarget.sim import BatchedSim, SimSettings
    from retarget.sim.world import build_world

    human = load_plugins().get("character", "human").cls()
    world = build_world(human)
    settings = SimSettings()
    sim = BatchedSim(world.model, world.layout, num_envs, settings)
    rng = np.random.default_rng(0)
    actions = torch.from_numpy(rng.uniform(-0.2, 0.2, (num_envs, world.layout.nu)).astype("f4"))
    for _ in range(5):
        sim.step(actions)
    rates = []
    for _ in range(3):
        t = time.perf_counter()
        for _ in range(steps):
            sim.step(actions)
        rates.append(steps * num_envs / (time.perf_counter() - t))
    return statistics.median(rates), f"human, {num_envs} worlds, {settings.substeps} substeps"


def end_to_end(num_envs: int, rollout_steps: int, iterations: int) -> dict[str, float]:
    env = human_env(num_envs)
    cfg = PPOConfig(rollout_steps=rollout_steps)
    ppo = PPOLearner(cfg, env.obs_dims, env.action_dim, num_envs, torch.Generator().manual_seed(0))
    rows = []
    for _ in range(iterations):
        t = time.perf_counter()
        s = ppo.train_iteration(env)
        rows.append((num_envs * rollout_steps / (time.perf_counter() - t), s))
    rest = rows[1:] or rows
    return {
        "total": statistics.median(r for r, _ in rest),
        "collect": statistics.median(s["collect_steps_per_s"] for _, s in rest),
        "update": statistics.median(s["update_samples_per_s"] for _, s in rest),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--batches", default="2048,8192,32768", help="rollout sizes")
    parser.add_argument("--threads", default="1,2", help="torch thread counts")
    parser.add_argument("--e2e", default="", help="NxT pairs, e.g. 128x64,256x32,512x16")
    parser.add_argument("--iterations", type=int, default=6, help="iterations per e2e setting")
    args = parser.parse_args()
    torch.set_num_threads(1)

    env = human_env(1)
    dims, action_dim = dict(env.obs_dims), env.action_dim
    del env
    print(f"torch {torch.__version__}, obs {dims}, actions {action_dim}")
    physics, what = physics_steps_per_s()
    print(f"physics ({what}): {physics:,.0f} env steps/s")
    print(f"{'samples':>8} {'threads':>7} {'update s':>9} {'samples/s':>10} {'physics/update':>15}")
    for samples in (int(b) for b in args.batches.split(",")):
        for threads in (int(t) for t in args.threads.split(",")):
            seconds = time_update(dims, action_dim, samples, threads)
            rate = samples / seconds
            print(
                f"{samples:>8} {threads:>7} {seconds:>9.3f} {rate:>10,.0f} {physics / rate:>15.2f}"
            )
    if args.e2e:
        print(f"\nend to end on the human env ({args.iterations} iterations each)")
        print(
            f"{'envs':>5} {'steps':>5} {'total/s':>8} {'collect/s':>9} {'update/s':>9} "
            f"{'total/physics':>13}"
        )
        for pair in args.e2e.split(","):
            n, t = (int(x) for x in pair.split("x"))
            r = end_to_end(n, t, args.iterations)
            print(
                f"{n:>5} {t:>5} {r['total']:>8,.0f} {r['collect']:>9,.0f} {r['update']:>9,.0f} "
                f"{r['total'] / physics:>13.2f}"
            )


if __name__ == "__main__":
    main()
