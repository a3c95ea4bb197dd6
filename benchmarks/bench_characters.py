"""Characters: Table 1 comparison, kinematic-retarget foot artefacts, physics stability.

Run: ``.venv/bin/python benchmarks/bench_characters.py [--clips DIR] [--seconds S]``

1. Table 1: mass, height, links and DoF of each built character next to the paper's targets.
2. Kinematic retargeting of every clip onto every character: joint-limit clipping rate, mean foot
   penetration, floating (while the human foot is in contact) and sliding (horizontal foot
   speed while the human foot stays in contact). The same sliding measure on the human's own
   ankle is printed as "source" for scale: a planted foot rolling heel to toe moves its ankle.
   These are the artefacts physics removes (paper Fig. 4); the numbers are the baseline.
3. Stability: each character on a floor under uniformly random actions in [-1, 1] changed at
   36 Hz, for a few physics timesteps; a "reset" is a non-finite or > 1000 rad/s state. This is
   what chose ``DEFAULT_TIMESTEP = 1/360`` (10 substeps per control step).
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import mujoco
import numpy as np

from retarget.character import kinematic as km
from retarget.character.builder import geom_z_extent
from retarget.motion.import_bvh import load_bvh
from retarget.motion.shared_data import require_clips, shared_data
from retarget.plugins.characters.dino import Dino
from retarget.plugins.characters.human import Human
from retarget.plugins.characters.jesse import Jesse
from retarget.plugins.characters.oppy import Oppy

CHARACTERS = (Human, Jesse, Dino, Oppy)
TABLE1 = {"human": (70.13, 1.75, 18, 32), "jesse": (60, 1.80, 16, 32),
          "dino": (180, 2.50, 30, 44), "oppy": (7, 0.80, 24, 58)}


def table1() -> None:
    print("## Table 1 (built vs target)")
    print(f"{'character':10s} {'mass kg':>14s} {'height m':>14s} {'links':>9s} {'DoF':>9s} "
          f"{'actuated':>8s} {'passive':>7s} {'density':>8s}")
    for cls in CHARACTERS:
        c = cls()
        m = c.build_spec().compile()
        d = mujoco.MjData(m)
        mujoco.mj_forward(m, d)
        low, high = geom_z_extent(m, d)
        tm, th, tl, td = TABLE1[c.name]
        print(f"{c.name:10s} {m.body_mass.sum():6.2f} / {tm:<6g} {high - low:6.3f} / {th:<6g} "
              f"{m.nbody - 1:3d} / {tl:<3d} {m.nv - 6:3d} / {td:<3d} {m.nu:8d} "
              f"{len(c.passive_joints()):7d} {c.built().density:8.0f}")


def source_sliding(clip) -> float:
    """Horizontal ankle speed of the human while its foot is labelled in contact (m/s)."""
    from retarget.motion import skeleton as sk

    ankles = clip.global_pos[:, list(sk.FEET), :2]
    speed = np.linalg.norm(np.diff(ankles, axis=0), axis=-1) * clip.fps
    held = clip.contacts[1:] & clip.contacts[:-1]
    return float(speed[held].mean()) if held.any() else 0.0


def artefacts(clip_dir: Path) -> None:
    paths = sorted(clip_dir.glob("*.bvh"))
    if not paths:
        print(f"no clips in {clip_dir}")
        return
    clips = [load_bvh(p) for p in paths]
    built = [(c, c.build_spec().compile()) for c in (cls() for cls in CHARACTERS)]
    print("\n## Kinematic retarget foot artefacts per clip "
          "(clip% | penetration cm | float cm | sliding m/s)")
    header = f"{'clip':44s} {'source':>7s}" + "".join(f" {c.name:>24s}" for c, _ in built)
    print(header)
    totals = {c.name: [] for c, _ in built}
    t_retarget = 0.0
    for path, clip in zip(paths, clips, strict=True):
        row = f"{path.stem[:44]:44s} {source_sliding(clip):7.3f}"
        for c, m in built:
            t0 = time.perf_counter()
            motion = km.retarget_clip(clip, m, c.joint_map())
            t_retarget += time.perf_counter() - t0
            a = km.foot_artefacts(m, motion, clip.contacts, c.body_groups())
            totals[c.name].append((motion.clip_rate, a.penetration, a.float, a.sliding))
            row += (f" {100 * motion.clip_rate:4.1f} {100 * a.penetration:5.2f} "
                    f"{100 * a.float:5.2f} {a.sliding:5.3f}")
        print(row)
    src = np.mean([source_sliding(c) for c in clips])
    print(f"\n## Mean over {len(clips)} clips (source ankle sliding {src:.3f} m/s)")
    for name, rows in totals.items():
        r = np.mean(rows, axis=0)
        print(f"{name:8s} clipped {100 * r[0]:5.2f}%  penetration {100 * r[1]:5.2f} cm  "
              f"float {100 * r[2]:5.2f} cm  sliding {r[3]:.3f} m/s")
    frames = sum(c.num_frames for c in clips) * len(built)
    print(f"retarget_clip: {frames / t_retarget:,.0f} frames/s (all joints of a frame at once)")


def _floor_world(spec: mujoco.MjSpec, dt: float) -> mujoco.MjModel:
    world = mujoco.MjSpec()
    world.option.timestep = dt
    world.option.integrator = spec.option.integrator
    spec.option.timestep = dt
    world.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 1])
    world.attach(spec, prefix="c/", frame=world.worldbody.add_frame())
    return world.compile()


def stability(seconds: float) -> None:
    print(f"\n## Random actions at 36 Hz for {seconds:g} s (resets = non-finite or >1000 rad/s)")
    print(f"{'character':10s} {'dt':>8s} {'substeps':>8s} {'resets':>7s} {'max |qvel|':>11s} "
          f"{'sim s/s':>8s}")
    for cls in CHARACTERS:
        for dt_inv, sub in ((360, 10), (216, 6), (144, 4)):
            c = cls()
            m = _floor_world(c.build_spec(), 1.0 / dt_inv)
            d = mujoco.MjData(m)
            rng = np.random.default_rng(0)
            resets, vmax = 0, 0.0
            t0 = time.perf_counter()
            for _ in range(round(seconds * 36)):
                d.ctrl[:] = rng.uniform(-1.0, 1.0, m.nu)
                for _ in range(sub):
                    mujoco.mj_step(m, d)
                v = np.abs(d.qvel).max()
                if not np.isfinite(d.qacc).all() or not np.isfinite(v) or v > 1e3:
                    resets += 1
                    mujoco.mj_resetData(m, d)
                else:
                    vmax = max(vmax, float(v))
            wall = time.perf_counter() - t0
            print(f"{c.name:10s} {'1/' + str(dt_inv):>8s} {sub:8d} {resets:7d} {vmax:11.0f} "
                  f"{seconds / wall:8.1f}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--clips", type=Path, default=shared_data("mocap"))
    parser.add_argument("--seconds", type=float, default=20.0,
                        help="simulated seconds per stability run")
    args = parser.parse_args(argv)
    require_clips(args.clips)  # before any work: the data is there
    warnings.simplefilter("ignore")
    table1()
    artefacts(args.clips)
    stability(args.seconds)
    return 0


if __name__ == "__main__":
    sys.exit(main())
