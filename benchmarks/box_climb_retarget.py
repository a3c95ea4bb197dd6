"""Kinematic retargets of a box-climb capture onto each character, boxes scaled with it:
how far the feet float above (or sink into) the box tops where the person stood on them.

Run: ``.venv/bin/python benchmarks/box_climb_retarget.py [--sequence seq_0]
[--characters human dino oppy]``

For every frame where the capture's foot rests on a box (its sole slower than the contact
labels' 0.4 m/s and above 10 cm of the floor), the character's lowest foot point (corners of
its foot geoms' boxes) is compared with the box top under it: ``gap`` > 0 floats, < 0 sinks.
Also printed: the reference's deepest penetration into any prop over the whole clip, and how
many resting frames the reference contact labels mark (foot touching a scene prop).
"""

from __future__ import annotations

import argparse

import mujoco
import numpy as np
import torch

from retarget.env.build import env_from_recipe
from retarget.motion.contacts import SPEED_THRESHOLD
from retarget.motion.shared_data import shared_data
from retarget.recipe import load
from retarget.registry.loader import load_plugins

RECIPE = "examples/recipes/box_climb_teacher.yaml"


def lowest_foot_points(env, qpos: np.ndarray, side: str) -> np.ndarray:
    """World (x, y, z) of each frame's lowest corner of the ``side`` foot's geoms."""
    model = env.world.model
    data = mujoco.MjData(model)
    bodies = [env.layout.body_ids[k] for k in env.layout.body_groups[f"{side}_foot"]]
    geoms = [g for g in range(model.ngeom) if model.geom_bodyid[g] in bodies]
    signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    out = np.zeros((len(qpos), 3))
    for f in range(len(qpos)):  # a benchmark: one kinematics pass per frame
        data.qpos[:] = qpos[f]
        mujoco.mj_kinematics(model, data)
        best = None
        for g in geoms:
            centre, half = model.geom_aabb[g, :3], model.geom_aabb[g, 3:]
            turn = data.geom_xmat[g].reshape(3, 3)
            corners = data.geom_xpos[g] + (centre + signs * half) @ turn.T
            low = corners[np.argmin(corners[:, 2])]
            if best is None or low[2] < best[2]:
                best = low
        out[f] = best
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sequence", default="seq_0")
    parser.add_argument("--characters", nargs="+", default=["human", "dino", "oppy"])
    args = parser.parse_args()
    registry = load_plugins()
    folder = shared_data("scenes/box_climb") / args.sequence
    print(f"{folder}")
    print(f"{'character':<10} {'scale':>6} {'boxes (m)':<20} {'rest frames':>11} "
          f"{'gap p50 cm':>10} {'p5':>6} {'p95':>6} {'labelled':>8} {'pen max cm':>10}")
    for name in args.characters:
        resolved = load(RECIPE, registry, shorthands={"character": name, "motions": str(folder)})
        env = env_from_recipe(resolved, num_envs=1, threads=1, registry=registry)
        q, lib = env.reference.qpos64, env.library
        env.place(torch.zeros(1, dtype=torch.long), torch.zeros(1, dtype=torch.long))
        pts = lib.global_pos.double().numpy()
        groups = list(env.layout.body_groups)
        gaps, labelled, rests = [], 0, 0
        for side, toe_joint in (("left", 4), ("right", 8)):
            toe = pts[:, toe_joint]
            speed = np.linalg.norm(np.gradient(toe, 1 / lib.fps, axis=0)[:, :2], axis=-1)
            rest = (speed < SPEED_THRESHOLD) & (toe[:, 2] > 0.1)  # the capture on a box
            low = lowest_foot_points(env, q[rest], side)
            top = env.scene.height_at(torch.as_tensor(low[None, :, :2]))[0].numpy()
            gaps.append(low[:, 2] - top)
            labels = env.reference.scene_contacts[torch.from_numpy(rest)]
            labelled += int(labels[:, groups.index(f"{side}_foot")].sum())
            rests += int(rest.sum())
        gap = np.concatenate(gaps) * 100
        deep, _ = env.sim.pose_penetration(q)  # one clip: its own boxes are the placement
        heights = ", ".join(f"{s.height:.2f}" for s in env.scene.fitted)
        scale = float(q[0, 2] / lib.root_pos[0, 2])
        print(f"{name:<10} {scale:6.2f} {heights:<20} {rests:>11} {np.median(gap):10.1f} "
              f"{np.percentile(gap, 5):6.1f} {np.percentile(gap, 95):6.1f} "
              f"{labelled / max(rests, 1):8.2f} {deep.max() * 100:10.1f}")


if __name__ == "__main__":
    main()
