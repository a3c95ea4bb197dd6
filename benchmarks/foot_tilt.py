"""How flat a character's feet stand on its references, with and without level feet.

    python benchmarks/foot_tilt.py                          # Bandai Namco held-out walks, runs
    python benchmarks/foot_tilt.py --motions ../shared/data/mocap --patterns 'cmu_*'

For each character and clip set: the foot's pitch while the human's foot is in contact
(median, and the share within 5 degrees of level), and the sole's float above and penetration
below the floor (``retarget.character.kinematic.foot_artefacts``), for the clips as read and
after :func:`retarget.motion.level_feet.level_feet`. Kinematic only: no simulation.
"""

from __future__ import annotations

import argparse

import numpy as np

from retarget.motion.shared_data import shared_data


def pitch_in_contact(model, qpos: np.ndarray, contacts: np.ndarray, body: int) -> np.ndarray:
    """Degrees of the foot body's forward axis above the ground at each contact frame."""
    import mujoco

    data = mujoco.MjData(model)
    out = []
    for i in np.flatnonzero(contacts):
        data.qpos[:] = qpos[i]
        mujoco.mj_kinematics(model, data)
        out.append(np.degrees(np.arcsin(np.clip(data.xmat[body][6], -1.0, 1.0))))
    return np.asarray(out)


def main() -> int:
    import mujoco

    import retarget
    from retarget.character.kinematic import foot_artefacts, retarget_clip
    from retarget.motion.level_feet import level_feet
    from retarget.motion.sources import load_motions
    from retarget.sim.world import build_world

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--motions", default=str(shared_data("mocap_corpus")))
    parser.add_argument("--patterns", default="*_walk_normal_*,*_run_normal_*")
    parser.add_argument("--characters", default="human,dino")
    parser.add_argument("--clips", type=int, default=6, help="clips per pattern")
    args = parser.parse_args()
    registry = retarget.load_plugins()
    print(f"{'character':9} {'clips':24} {'level':>5} {'pitch deg':>9} {'within 5':>8} "
          f"{'float mm':>8} {'penetr. mm':>10}")
    for name in args.characters.split(","):
        character = registry.get("character", name).cls
        inst = character(character.Config())
        model = build_world(inst).model
        joint_map, groups = inst.joint_map(), inst.body_groups()
        feet = {k: groups[k] for k in ("left_foot", "right_foot")}
        left = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, groups["left_foot"][0])
        for pattern in args.patterns.split(","):
            clips = load_motions(args.motions, registry.motion_formats(), include=[pattern],
                                 progress=False)[: args.clips]  # fmt: skip
            for level in (False, True):
                pitches, floats, pens = [], [], []
                for clip in clips:
                    c = level_feet(clip) if level else clip
                    motion = retarget_clip(c, model, joint_map)
                    pitches.append(pitch_in_contact(model, motion.qpos, c.contacts[:, 0], left))
                    art = foot_artefacts(model, motion, c.contacts, feet)
                    floats.append(art.float)
                    pens.append(art.penetration)
                p = np.concatenate(pitches)
                print(f"{name:9} {pattern:24} {level!s:>5} {np.median(p):9.1f} "
                      f"{np.mean(np.abs(p) < 5):8.2f} {1e3 * np.mean(floats):8.1f} "
                      f"{1e3 * np.mean(pens):10.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
