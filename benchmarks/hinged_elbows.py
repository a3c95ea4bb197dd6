"""Where the human's retargeted hands are against the controllers the performer held, with
the elbow's bend alone and with elbows as hinges (``env.hinge_elbows``), and a picture.

    python benchmarks/hinged_elbows.py --out benchmarks/results/hinged_elbows.json \
        --picture benchmarks/results/hinged_elbows.png

Each shared clip (``../shared/data/mocap`` or ``$RETARGET_SHARED_DATA/mocap``) is scaled to
the character as a run with devices at the character's size does, retargeted onto the human
both ways, and its hand sites (where a controller is held) compared with the controllers
synthesised from the clip's own wrists. Prints a table and writes the figures as JSON; the
picture shows frames of an arm wave, controllers as red balls, bend alone above and hinged
below.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import torch

CLIPS = ("bandai_d2_walk_normal_020.bvh", "bandai_d2_run_normal_040.bvh",
         "bandai_d2_wave-both-hands_normal_012.bvh", "bandai_d2_raise-up-both-hands_normal_064.bvh",
         "cmu_131_01_walk_start_stop.bvh")  # fmt: skip
PICTURE_CLIP = "bandai_d2_wave-both-hands_normal_012.bvh"


def retargeted(clip, hinge: bool):
    """The human, its reference of ``clip`` (scaled to it) and the controllers ``(T, 2, 3)``."""
    from retarget.character.kinematic import root_height_ratio, scaled_clip
    from retarget.env.reference import CharacterReference
    from retarget.motion.devices import device_poses
    from retarget.plugins.characters.human import Human
    from retarget.sim.world import build_world

    human = Human()
    world = build_world(human)
    clip = scaled_clip(clip, root_height_ratio(world.model, clip))
    ref = CharacterReference(human, world.model, world.layout, [clip], hinge=hinge)
    controllers = device_poses(clip.global_pos, clip.global_rot, clip.height)[:, 1:3, :3]
    return world, ref, controllers


def hand_gap(clip, hinge: bool) -> dict[str, float]:
    world, ref, controllers = retargeted(clip, hinge)
    hands = [world.layout.site("left_hand"), world.layout.site("right_hand")]
    held = ref.pose(torch.arange(clip.num_frames)).site_pos[:, hands].double().numpy()
    gap = np.linalg.norm(held - controllers, axis=-1)
    return {"mean_cm": float(gap.mean() * 100), "p90_cm": float(np.percentile(gap, 90) * 100)}


def picture(clip, out: Path, frames: int = 4, size: int = 300) -> None:
    import mujoco

    from retarget.render.character_view import label
    from retarget.render.gl import ensure_offscreen
    from retarget.render.motion import add_decor_geom, contact_sheet, write_png

    ensure_offscreen()
    picks = np.linspace(0.15, 0.85, frames) * (clip.num_frames - 1)
    rows = []
    for hinge in (False, True):
        world, ref, controllers = retargeted(clip, hinge)
        model, data = world.model, mujoco.MjData(world.model)
        renderer = mujoco.Renderer(model, size, size)
        try:
            images = []
            for f in picks.astype(int):
                data.qpos[: ref.qpos64.shape[1]] = ref.qpos64[f]
                mujoco.mj_kinematics(model, data)
                cam = mujoco.MjvCamera()
                cam.lookat[:] = data.qpos[:3] + np.array([0.0, 0.0, 0.25])
                cam.distance, cam.elevation = 2.6, -10.0
                heading = data.xmat[1].reshape(3, 3)[:, 0]
                cam.azimuth = float(np.degrees(np.arctan2(heading[1], heading[0]))) + 150.0
                renderer.update_scene(data, camera=cam)
                for c in controllers[f]:
                    add_decor_geom(mujoco, renderer.scene, int(mujoco.mjtGeom.mjGEOM_SPHERE),
                                   [0.035], c, (0.9, 0.1, 0.1, 1.0))  # fmt: skip
                images.append(renderer.render().copy())
        finally:
            renderer.close()
        text = "hinged elbows" if hinge else "the elbow's bend alone"
        rows.append(label(contact_sheet(np.stack(images), columns=frames),
                          [(0.5, 0.06, f"{text}: controllers in red")]))  # fmt: skip
    write_png(out, np.concatenate(rows, axis=0))


def main() -> int:
    from retarget.motion.import_bvh import load_bvh
    from retarget.motion.shared_data import shared_data

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, help="JSON of the figures")
    parser.add_argument("--picture", type=Path, help="PNG: bend alone above, hinged below")
    args = parser.parse_args()
    folder = shared_data("mocap")
    if not (folder / CLIPS[0]).is_file():
        raise SystemExit(f"shared mocap clips not found at {folder} (set RETARGET_SHARED_DATA)")
    results = {}
    print(f"{'clip':44s} {'bend alone cm':>14s} {'hinged cm':>10s}  (mean; p90)")
    for name in CLIPS:
        clip = load_bvh(folder / name)
        before, after = hand_gap(clip, False), hand_gap(clip, True)
        results[name] = {"bend_alone": before, "hinged": after}
        print(f"{name:44s} {before['mean_cm']:6.1f}; {before['p90_cm']:5.1f} "
              f"{after['mean_cm']:6.1f}; {after['p90_cm']:5.1f}")
    if args.out:
        args.out.write_text(json.dumps(results, indent=1))
        print(f"wrote {args.out}")
    if args.picture:
        picture(load_bvh(folder / PICTURE_CLIP), args.picture)
        print(f"wrote {args.picture}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
