"""MuJoCo Warp against MuJoCo's C engine, per built-in character: does ``sim.backend: warp``
simulate the same thing?

Run: ``.venv/bin/python benchmarks/warp_vs_c.py [--characters human,jesse,dino,oppy]
[--num-envs 4] [--steps 100] [--out benchmarks/results/warp_vs_c_DATE.md]``

For each character two environments of the packaged recipe (three-point sensors, the
character's defaults, terminations off so nothing resets differently) start at the same
reference frames and receive the same random actions:

1. one control step from the same state: the largest difference of qpos, qvel, body
   positions, per-body contact force and the number of contacts per world;
2. a rollout of ``--steps`` control steps: the root's position gap and the joints' RMS angle
   gap at steps 1, 10, 50 and the last (chaotic contact dynamics let small float32/float64
   differences grow: the question is how fast).

Needs ``pip install 'retarget[warp]'``; runs on the CPU (slowly) or a GPU.
"""

from __future__ import annotations

import argparse
import datetime as dt
import time
from pathlib import Path

import numpy as np
import torch

from retarget.env.build import env_from_recipe
from retarget.recipe import load
from retarget.registry.loader import load_plugins
from retarget.sim.warp_backend import import_warp

RECIPE = """\
extends: null
name: warp-check
seed: 3
character: {character}
sensors: [three_point]
rewards:
  joint_pos: {{weight: 1.0, k: 25.0}}
algorithm: {{type: ppo}}
env: {{num_envs: {num_envs}}}
sim: {{threads: 1, backend: {backend}}}
"""


def contact_counts(env) -> np.ndarray:
    """Contacts per world as each engine found them (Warp's own list, C's ``ncon``)."""
    sim = env.sim
    if type(sim).__name__ == "WarpSim":
        n = int(sim.data.nacon.numpy()[0])
        world = sim.data.contact.worldid.numpy()[:n]
        return np.bincount(world, minlength=env.num_envs)
    return np.asarray(sim.each_env(lambda d: d.ncon))


def make(character: str, backend: str, num_envs: int, tmp: Path, registry):
    path = tmp / f"{character}-{backend}.yaml"
    path.write_text(RECIPE.format(character=character, backend=backend, num_envs=num_envs))
    return env_from_recipe(load(path, registry), registry=registry, terminations=False)


def compare(character: str, num_envs: int, steps: int, tmp: Path, registry) -> dict:
    warp, c = (make(character, b, num_envs, tmp, registry) for b in ("warp", "mujoco"))
    clip = torch.zeros(num_envs, dtype=torch.long)
    frame = torch.arange(num_envs) * 7 + 2
    for env in (warp, c):
        env.place(clip, frame)
    gen = torch.Generator().manual_seed(0)
    actions = [(torch.rand(num_envs, c.action_dim, generator=gen) - 0.5) * 0.6
               for _ in range(steps)]  # fmt: skip
    row: dict = {"character": character}
    seconds = {"warp": 0.0, "mujoco": 0.0}
    gaps = {}
    for k, action in enumerate(actions, start=1):
        t0 = time.perf_counter()
        warp.step(action)
        t1 = time.perf_counter()
        c.step(action)
        seconds["warp"] += t1 - t0
        seconds["mujoco"] += time.perf_counter() - t1
        a, b = warp.sim.state, c.sim.state
        if k == 1:
            row["qpos"] = float((a.qpos - b.qpos).abs().max())
            row["qvel"] = float((a.qvel - b.qvel).abs().max())
            row["body_pos"] = float((a.body_pos - b.body_pos).abs().max())
            row["force"] = float((a.contact_force - b.contact_force).abs().max())
            row["weight"] = float(c.world.model.body_mass.sum() * 9.81)
            cw, cc = contact_counts(warp), contact_counts(c)
            row["contacts"] = f"{cw.sum()} / {cc.sum()}"
        root = float((a.body_pos[:, 0] - b.body_pos[:, 0]).norm(dim=-1).max())
        joints = float((a.qpos[:, 7:] - b.qpos[:, 7:]).square().mean().sqrt())
        gaps[k] = (root, joints)
    for k in (1, 10, 50, steps):
        if k in gaps:
            row[f"root@{k}"], row[f"joint@{k}"] = gaps[k]
    row["ms_warp"] = 1e3 * seconds["warp"] / steps
    row["ms_c"] = 1e3 * seconds["mujoco"] / steps
    row["warp_overflows"] = warp.sim.overflows
    return row


def table(rows: list[dict], steps: int) -> str:
    marks = [k for k in (1, 10, 50, steps) if f"root@{k}" in rows[0]]
    head = ["character", "qpos", "qvel", "body pos m", "force N (weight)", "contacts W / C"]
    head += [f"root m / joint rad @{k}" for k in marks] + ["ms/step W", "ms/step C"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        cells = [r["character"], f"{r['qpos']:.1e}", f"{r['qvel']:.1e}", f"{r['body_pos']:.1e}",
                 f"{r['force']:.2f} ({r['weight']:.0f})", r["contacts"]]  # fmt: skip
        cells += [f"{r[f'root@{k}']:.1e} / {r[f'joint@{k}']:.1e}" for k in marks]
        cells += [f"{r['ms_warp']:.0f}", f"{r['ms_c']:.1f}"]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--characters", default="human,jesse,dino,oppy")
    parser.add_argument("--num-envs", type=int, default=4)
    parser.add_argument("--steps", type=int, default=100)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    wp, _ = import_warp()
    registry = load_plugins()
    tmp = Path("/tmp") / "retarget-warp-check"
    tmp.mkdir(exist_ok=True)
    rows = []
    for name in args.characters.split(","):
        print(f"{name} ...", flush=True)
        rows.append(compare(name, args.num_envs, args.steps, tmp, registry))
    device = wp.get_preferred_device()
    text = (f"{args.num_envs} worlds, {args.steps} control steps, Warp on {device.alias} "
            f"({device.name})\n\n{table(rows, args.steps)}\n")  # fmt: skip
    print(text)
    if args.out is not None:
        args.out.write_text(f"<!-- {dt.date.today()} -->\n{text}")


if __name__ == "__main__":
    main()
