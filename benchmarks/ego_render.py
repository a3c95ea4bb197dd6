"""Headset-camera rendering cost: ms per frame for a whole rig, and cache size per minute.

Run: ``.venv/bin/python benchmarks/ego_render.py [--frames 60]``

Renders a generated walk from each packaged rig (``quest2``: 4 cameras, ``aria``: 2) at a few
resolutions on this machine's CPU (OSMesa), after one warm-up frame, and prints ms per rig
frame, frames per second, and the cache a minute of 36 Hz motion takes (uint8 grayscale).
The plain MuJoCo offscreen render of one empty 64x48 frame is measured in the same run as the
baseline.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from retarget.motion.camera_rigs import RIGS
from retarget.motion.devices import device_poses
from retarget.motion.procedural import default_motions
from retarget.render.ego import EgoRenderer

SIZES = ((40, 30), (80, 60), (160, 120))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=60)
    args = parser.parse_args()
    walk = next(c for c in default_motions() if c.name.startswith("walk"))
    heads = device_poses(walk.global_pos, walk.global_rot, walk.height)[:, 0]
    frames = range(min(args.frames, walk.num_frames))
    print(f"{'rig':<7} {'size':>8} {'ms/frame':>9} {'frames/s':>9} {'MB/min @36Hz':>13}")
    for name, rig in RIGS.items():
        for w, h in SIZES:
            with EgoRenderer(rig, w, h) as render:
                render(walk.global_pos[0], heads[0], walk.height)  # warm-up
                t0 = time.perf_counter()
                for f in frames:
                    render(walk.global_pos[f], heads[f], walk.height)
                ms = (time.perf_counter() - t0) / len(frames) * 1e3
            mb = 36 * 60 * len(rig.cameras) * w * h / 1e6
            print(f"{name:<7} {w:>4}x{h:<3} {ms:>9.1f} {1e3 / ms:>9.1f} {mb:>13.1f}")
    base = EgoRenderer(RIGS["aria"].model_copy(update={"cameras": RIGS["aria"].cameras[:1]}),
                       64, 48)  # fmt: skip
    with base:
        far = np.full_like(walk.global_pos[0], 1e3)
        t0 = time.perf_counter()
        for _ in range(30):
            base(far, heads[0], walk.height)
        print(f"baseline: one camera, nothing drawn, 64x48: "
              f"{(time.perf_counter() - t0) / 30 * 1e3:.1f} ms")


if __name__ == "__main__":
    main()
