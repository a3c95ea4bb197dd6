"""Long random-action runs: 10 000 control steps of N = 64 environments per character.

Run: ``.venv/bin/python benchmarks/random_actions.py [--steps 10000] [--num-envs 64]
[--characters human,jesse,dino,oppy] [--scale 1.0]``

Uniform random actions in ``[-scale, scale]`` (full torque range by default) drive every
environment; episodes end by the recipe's terminations and restart from random reference
frames. Prints per character: terminations by kind, non-finite resets, mean episode length,
whether any observation or reward was ever non-finite, and env steps/s. The test suite runs a
short version (64 envs x 157 steps); this is the long one.
"""

from __future__ import annotations

import argparse
import time

import torch

from retarget.env.build import env_from_recipe
from retarget.env.env import random_actions
from retarget.recipe import load
from retarget.registry.loader import load_plugins


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=10_000)
    parser.add_argument("--num-envs", type=int, default=64)
    parser.add_argument("--characters", default="human,jesse,dino,oppy")
    parser.add_argument("--scale", type=float, default=1.0)
    args = parser.parse_args()
    torch.set_num_threads(1)
    registry = load_plugins()
    for name in args.characters.split(","):
        resolved = load(None, registry, shorthands={"character": name}, assignments=[])
        env = env_from_recipe(resolved, num_envs=args.num_envs)
        g = torch.Generator().manual_seed(0)
        obs = env.reset()
        finite, lengths = True, []
        start = time.perf_counter()
        for _ in range(args.steps):
            obs, reward, _, _, info = env.step(random_actions(env, g, args.scale))
            finite &= bool(torch.isfinite(reward).all())
            finite &= all(bool(torch.isfinite(v).all()) for v in obs.values())
            if "episode" in info:
                lengths += info["episode"]["length"].tolist()
        seconds = time.perf_counter() - start
        mean_len = sum(lengths) / max(len(lengths), 1)
        print(
            f"{name}: {args.steps} control steps x {args.num_envs} envs in {seconds:.0f} s "
            f"({args.steps * args.num_envs / seconds:,.0f} env steps/s); terminations "
            f"{env.termination_counts}; non-finite resets {env.nan_resets}; "
            f"{len(lengths)} episodes, mean length {mean_len:.1f} steps; "
            f"observations and rewards always finite: {finite}"
        )


if __name__ == "__main__":
    main()
