"""Write ``walk_openxr.jsonl``: a sample headset + controller recording, generated.

The poses are where a headset and two controllers would be on the project's generated walk
(:func:`retarget.motion.devices.device_poses`), on a headset clock that does not start at 0,
in the OpenXR convention (y up), with the left controller lost for a quarter second, as a
real stream would be. Run: ``python examples/recordings/make_sample.py``; play a trained run
with it: ``retarget play RUN --input examples/recordings/walk_openxr.jsonl --out me.gif``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from retarget.motion.device_recording import DeviceRecording, write_recording
from retarget.motion.devices import device_poses
from retarget.motion.procedural import default_motions

HERE = Path(__file__).resolve().parent
SAMPLE = HERE / "walk_openxr.jsonl"
SECONDS = 6.0


def sample() -> DeviceRecording:
    walk = next(c for c in default_motions() if c.name.startswith("walk"))
    count = min(walk.num_frames, int(SECONDS * walk.fps))
    poses = device_poses(walk.global_pos, walk.global_rot, walk.height)[:count]
    times = 1234.5 + np.arange(count) / walk.fps  # a headset clock, not starting at 0
    tracked = np.ones(poses.shape[:2], dtype=bool)
    lost = slice(int(2.0 * walk.fps), int(2.25 * walk.fps))
    tracked[lost, 1] = False  # the left controller out of the cameras' view
    return DeviceRecording(times, poses, tracked)


def main() -> None:
    path = write_recording(SAMPLE, sample(), convention="openxr")
    print(f"wrote {path} ({len(path.read_text().splitlines()) - 1} samples)")


if __name__ == "__main__":
    main()
