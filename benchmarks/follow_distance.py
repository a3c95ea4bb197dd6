"""Does a trained character walk *with* its reference? Root distance and distance covered.

What ``retarget play`` shows as pictures, in numbers: the policy drives environment 0 from the
start of one clip (no early termination, as in ``play``), and once a second this prints how far
the simulated root is from the retargeted reference root, how far each has moved from its start,
and the top of the body (a fallen or hunched character is low). Usage::

    .venv/bin/python benchmarks/follow_distance.py runs/learning/dino-hmd-pd/latest \\
        --motions runs/learning/motions/train --clip 4 --seconds 8
"""

from __future__ import annotations

import argparse

import mujoco
import numpy as np
import torch
from rollout_args import add_rollout_args

from retarget.registry.loader import load_plugins
from retarget.render.policy_video import copy_env_pose
from retarget.train.load import load_run


def follow(run: str, motions: str | None, clip: int, seconds: float) -> None:
    loaded = load_run(run, load_plugins(strict=False), num_envs=1, motions=motions)
    env, lib = loaded.env, loaded.env.library
    hz = env.sim.settings.control_hz
    steps = int(min(seconds * hz, int(lib.length[clip]) - 2))
    data = mujoco.MjData(env.world.model)
    obs = env.place(torch.full((1,), clip), torch.full((1,), 0))
    sim_xy, ref_xy, tops = [], [], []
    with torch.no_grad():
        for _ in range(steps):
            obs, *_ = env.step(loaded.algorithm.act(obs))
            row = int(lib.rows(env.clip[:1], env.frame[:1])[0, 0])
            copy_env_pose(env, 0, data)
            sim_xy.append(data.qpos[:2].copy())
            ref_xy.append(env.reference.pose(torch.tensor([row])).qpos[0, :2].numpy())
            tops.append(float(env.sim.state.body_pos[0, :, 2].max()))
    sim, ref = np.array(sim_xy), np.array(ref_xy)
    dist = np.linalg.norm(sim - ref, axis=1)
    print(f"{run}: {lib.names[clip]}, {steps / hz:.1f} s")
    for t in range(0, steps, int(hz)):
        print(f"t={t / hz:4.1f} s  root to reference {dist[t]:.2f} m  reference moved "
              f"{np.linalg.norm(ref[t] - ref[0]):5.2f} m  character moved "
              f"{np.linalg.norm(sim[t] - sim[0]):5.2f} m  body top {tops[t]:.2f} m")  # fmt: skip
    length = [np.linalg.norm(np.diff(p, axis=0), axis=1).sum() for p in (ref, sim)]
    print(f"path: reference {length[0]:.2f} m, character {length[1]:.2f} m; "
          f"root to reference: mean {dist.mean():.2f} m, max {dist.max():.2f} m")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_rollout_args(parser)
    args = parser.parse_args()
    follow(args.run, args.motions, args.clip, args.seconds)


if __name__ == "__main__":
    main()
