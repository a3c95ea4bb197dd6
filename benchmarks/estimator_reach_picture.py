"""The shipped pose estimator on one clip with its wrists' reach off and on, side by side:
the character placed in the estimate, the performer as a blue ghost skeleton, the devices as
yellow boxes; four frames of each, cropped to the upper body.

    python benchmarks/estimator_reach_picture.py CLIP.bvh results/estimator_reach.png
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import retarget
from retarget.render.character_view import label, save_image
from retarget.render.estimate_video import Shot, render_estimate
from retarget.train.load import load_run


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("clip", help="a motion file (held out: never trained on)")
    parser.add_argument("out", type=Path, help="PNG to write")
    parser.add_argument("--run", default="pretrained:human-three_point-estimator")
    parser.add_argument("--seconds", type=float, default=4.0)
    args = parser.parse_args()
    registry = retarget.load_plugins()
    rows = []
    for reach, text in (("false", "network alone"),
                        ("true", "wrists reached along the performer's arm")):  # fmt: skip
        loaded = load_run(args.run, registry, motions=args.clip,
                          assignments=[f"algorithm.reach_controllers={reach}"])  # fmt: skip
        frames = render_estimate(loaded.env, loaded.algorithm.pose_estimator(), 0,
                                 seconds=args.seconds, shot=Shot(640, 480, 180.0, -5.0))
        picks = [frames[i] for i in np.linspace(10, len(frames) - 1, 4).astype(int)]
        strip = np.concatenate([f[20:280, 200:440] for f in picks], axis=1)
        rows.append(label(strip, [(0.5, 0.06, text)]))
    save_image(np.concatenate(rows, axis=0), args.out)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
