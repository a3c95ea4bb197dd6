"""Environment steps per second on MuJoCo Warp against MuJoCo's C engine, for a GPU.

Run: ``.venv/bin/python benchmarks/warp_speed.py [--character human] [--num-envs 64,1024,4096]
[--seconds 10] [--out FILE.md]``

Each row builds the packaged three-point recipe for the character with ``--num-envs`` worlds
on each backend (C on every core of the machine, Warp on its preferred device: the GPU when
there is one) and times whole environment steps (physics, host copy, sensors, rewards,
observations) with random actions, after a warm-up that compiles Warp's kernels and captures
its CUDA graph. The C column is skipped above ``--max-c-envs`` (it is linear in the worlds).
On a CPU-only machine Warp runs on the CPU and the table only shows that it works.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import torch

from retarget.env.build import env_from_recipe
from retarget.recipe import load
from retarget.registry.loader import load_plugins
from retarget.sim.warp_backend import import_warp

RECIPE = """\
extends: null
name: warp-speed
seed: 0
character: {character}
sensors: [three_point]
rewards:
  joint_pos: {{weight: 1.0, k: 25.0}}
terminations:
  fall: {{}}
algorithm: {{type: ppo}}
env: {{num_envs: {num_envs}}}
sim: {{threads: 0, backend: {backend}}}
"""


def rate(character: str, backend: str, num_envs: int, seconds: float, registry) -> float:
    path = Path("/tmp") / f"retarget-speed-{character}-{backend}.yaml"
    path.write_text(RECIPE.format(character=character, backend=backend, num_envs=num_envs))
    env = env_from_recipe(load(path, registry), registry=registry)
    gen = torch.Generator().manual_seed(0)
    env.reset()

    def act() -> torch.Tensor:
        return (torch.rand(num_envs, env.action_dim, generator=gen) - 0.5) * 0.6

    for _ in range(3):  # compile, capture, warm caches
        env.step(act())
    steps, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        env.step(act())
        steps += 1
    return steps * num_envs / (time.perf_counter() - t0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--character", default="human")
    parser.add_argument("--num-envs", default="64,1024,4096")
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--max-c-envs", type=int, default=4096)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    wp, _ = import_warp()
    device = wp.get_preferred_device()
    registry = load_plugins()
    torch.set_num_threads(1)
    lines = [f"{args.character}, Warp on {device.alias} ({device.name})", "",
             "| worlds | C env steps/s | Warp env steps/s | Warp / C |", "|---|---|---|---|"]
    for n in (int(x) for x in args.num_envs.split(",")):
        c = None
        if n <= args.max_c_envs:
            c = rate(args.character, "mujoco", n, args.seconds, registry)
        w = rate(args.character, "warp", n, args.seconds, registry)
        c_cell, ratio = (f"{c:.0f}", f"{w / c:.2f}") if c else ("-", "-")
        lines.append(f"| {n} | {c_cell} | {w:.0f} | {ratio} |")
        print(lines[-1], flush=True)
    text = "\n".join(lines) + "\n"
    print(text)
    if args.out is not None:
        args.out.write_text(text)


if __name__ == "__main__":
    main()
