"""How far each character's reference stands off the floor, with and without ``env.ground_feet``.

    python benchmarks/reference_ground.py --characters human,dino --max-clips 4
    python benchmarks/reference_ground.py --characters dino --kinds run --out results/x.json

For held-out clips of the Bandai Namco corpus (style ``normal``; ``--max-clips`` per kind),
each character's reference is built as training builds it (the packaged teacher recipe:
level feet, clips scaled to the character) and measured per frame: the lowest point of the
feet the performer has down (stance height, cm: above the floor is positive), the root force
a free-floating inverse asks for in frames where no geom is within 2 cm of the floor (the
body is in the air, so a force there is one nothing can give; in units of body weight), and
the share of such frames. Kinematics only: seconds per character.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import mujoco
import numpy as np
from heldout_eval import KINDS, corpus_files

from retarget.character.grounding import stance_heights
from retarget.env.build import env_from_recipe
from retarget.env.reference import foot_bodies
from retarget.recipe import load
from retarget.registry.loader import load_plugins

AIR_MARGIN = 0.02
"""A frame is in the air when no geom of the body is within this of anything (m)."""


def measure(env) -> dict[str, np.ndarray]:
    """Per frame of the env's library: stance height (m; NaN with no foot down), whether the
    body is in the air, and the root force the reference asks for (units of body weight)."""
    model, ref = env.world.model, env.reference
    qpos, qvel = ref.qpos64, ref.qvel64
    feet = foot_bodies(env.layout, env.character.name)
    stance = stance_heights(model, qpos, env.library.contacts.numpy(), feet)
    free = model.__copy__()
    free.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    near = model.__copy__()
    near.geom_margin[:] = np.maximum(near.geom_margin, AIR_MARGIN)
    d_free, d_near = mujoco.MjData(free), mujoco.MjData(near)
    weight = float(model.body_subtreemass[1]) * 9.81
    nq, nv = qpos.shape[1], qvel.shape[1]
    air = np.zeros(len(qpos), dtype=bool)
    force = np.zeros(len(qpos))
    starts, lengths = env.library.start.numpy(), env.library.length.numpy()
    for a, n in zip(starts, lengths, strict=True):  # accelerations within each clip
        clip_vel = qvel[a : a + n]
        acc = np.gradient(clip_vel, 1.0 / env.library.fps, axis=0) if n > 1 else 0 * clip_vel
        for t in range(n):
            d_near.qpos[:nq] = qpos[a + t]
            mujoco.mj_kinematics(near, d_near)
            mujoco.mj_collision(near, d_near)
            air[a + t] = d_near.ncon == 0
            d_free.qpos[:nq], d_free.qvel[:nv], d_free.qacc[:nv] = qpos[a + t], qvel[a + t], acc[t]
            mujoco.mj_inverse(free, d_free)
            force[a + t] = np.linalg.norm(d_free.qfrc_inverse[:3]) / weight
    return {"stance": stance, "air": air, "force": force}


def summary(m: dict[str, np.ndarray]) -> dict[str, float]:
    stance = m["stance"][np.isfinite(m["stance"])]
    air = m["air"]
    return {
        "stance_median_cm": float(100 * np.median(stance)) if stance.size else float("nan"),
        "stance_abs_mean_cm": float(100 * np.abs(stance).mean()) if stance.size else float("nan"),
        "air_share": float(air.mean()),
        "air_force_body_weights": float(m["force"][air].mean()) if air.any() else 0.0,
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--characters", default="human,dino")
    parser.add_argument("--kinds", default=",".join(KINDS))
    parser.add_argument("--style", default="normal")
    parser.add_argument("--max-clips", type=int, default=4)
    parser.add_argument("--out", default=None, help="JSON of the figures")
    args = parser.parse_args()
    registry = load_plugins()
    figures: dict[str, dict] = {}
    for name in args.characters.split(","):
        for kind in args.kinds.split(","):
            files = corpus_files(args.style, kind, args.max_clips)
            for ground in (False, True):
                resolved = load(None, registry, shorthands={"character": name},
                                assignments=[f"env.ground_feet={str(ground).lower()}"])  # fmt: skip
                env = env_from_recipe(resolved, num_envs=1, motions=str(files[0].parent),
                                      include=[f.name for f in files])  # fmt: skip
                row = summary(measure(env))
                label = "grounded" if ground else "as retargeted"
                figures.setdefault(name, {}).setdefault(kind, {})[label] = row
                print(f"{name:6s} {kind:8s} {label:14s} "
                      f"stance {row['stance_median_cm']:+5.1f} cm median, "
                      f"{row['stance_abs_mean_cm']:4.1f} cm mean off the floor; in the air "
                      f"{row['air_share']:.2f} of frames, asking "
                      f"{row['air_force_body_weights']:.2f} body weights there")
    if args.out:
        report = {"clips_per_kind": args.max_clips, "style": args.style, **figures}
        Path(args.out).write_text(json.dumps(report, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
