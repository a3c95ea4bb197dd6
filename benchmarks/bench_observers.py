"""Scene observers: cost of ``height_map`` and ``point_cloud`` against one environment step.

Run: ``.venv/bin/python benchmarks/bench_observers.py [--envs 256] [--steps 5] [--threads 1]``

A human in the living room (five randomized props) with both observers. One environment step
(physics, reference, rewards, terminations, resets and every observation source) is timed over
``--steps`` zero-action steps; then each observer's ``observe`` alone is timed on the step's
context, both right after resets (the point cloud re-places the reset environments' pools) and
in a steady step. Figures are ratios against the env step measured in the same run, since
these machines are noisy.
"""

from __future__ import annotations

import argparse
import time

import torch

from retarget.env.build import env_from_recipe
from retarget.motion.procedural import default_motions
from retarget.recipe import load
from retarget.registry.loader import load_plugins


def best(fn, repeats: int) -> float:
    """Best of ``repeats`` wall times of ``fn()`` (the least disturbed by other load)."""
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--envs", type=int, default=256)
    parser.add_argument("--steps", type=int, default=5)
    parser.add_argument("--threads", type=int, default=1)
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    resolved = load(
        None,
        load_plugins(strict=True),
        shorthands={"character": "human", "observers": "height_map,point_cloud"},
        assignments=["scene=living_room"],
    )
    env = env_from_recipe(
        resolved, num_envs=args.envs, threads=args.threads, clips=default_motions()[:2]
    )
    zeros = torch.zeros(args.envs, env.action_dim)
    env.reset()
    env.step(zeros)  # warm up
    step = best(lambda: env.step(zeros), args.steps)
    ctx = env._context(zeros)
    height_map, point_cloud = env.observers
    hm = best(lambda: height_map.observe(ctx), 10)
    pc_steady = best(lambda: point_cloud.observe(ctx), 10)

    def after_reset() -> None:
        point_cloud.reset(torch.arange(0, args.envs, 16))  # 1 in 16 envs reset this step
        point_cloud.observe(ctx)

    pc_reset = best(after_reset, 5)
    print(f"envs {args.envs}, torch threads {args.threads}, scene living_room, character human")
    print(f"env step (both observers included)  {step * 1e3:8.1f} ms")
    print(f"height_map observe                  {hm * 1e3:8.2f} ms  {hm / step:6.1%} of a step")
    print(
        f"point_cloud observe (steady)        {pc_steady * 1e3:8.2f} ms  "
        f"{pc_steady / step:6.1%} of a step"
    )
    print(
        f"point_cloud observe (1/16 reset)    {pc_reset * 1e3:8.2f} ms  "
        f"{pc_reset / step:6.1%} of a step"
    )


if __name__ == "__main__":
    main()
