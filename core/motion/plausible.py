"""Motion that parses but cannot be a person: refused with the file and frame named.

A file can pass every format check and still make training meaningless: a skeleton scaled
by mistake (a 175 km subject from metres read as microns), or a root that leaves the room
between two frames (a corrupt value, a glitch of the capture). Retargeting then scales the
character's motion by the same absurd factor, or resets place it kilometres away. These
checks run on every reader's canonical clip, before anything downstream sees it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from retarget.errors import MotionError
from retarget.motion.clip import MotionClip

HEIGHT_RANGE = (0.4, 3.0)
"""Standing heights a subject may have, metres (a toddler to the tallest adults, with room)."""
MAX_DISTANCE = 1000.0
"""Farthest a root may be from the origin, metres (a large capture volume is tens)."""
MAX_SPEED = 50.0
"""Fastest a root may move between two frames, m/s (a sprinter runs about 12)."""


def check_plausible(clip: MotionClip, file: str | Path | None) -> MotionClip:
    """``clip`` unchanged, or a :class:`MotionError` saying what no person does."""
    height = clip.height
    lo, hi = HEIGHT_RANGE
    if not lo <= height <= hi:
        raise MotionError(
            f"the skeleton stands {height:.3g} m tall, outside {lo}-{hi} m: wrong units or a "
            "scaled skeleton", file=file,
            hint="give the reader's units (e.g. motions.format: {type: bvh, units: cm})",
        )  # fmt: skip
    far = np.abs(clip.root_pos).max(axis=1)
    if clip.num_frames and float(far.max()) > MAX_DISTANCE:
        frame = int(np.argmax(far > MAX_DISTANCE))
        raise MotionError(
            f"frame {frame}: the root is {float(far[frame]):.3g} m from the origin (more than "
            f"{MAX_DISTANCE:g} m): a corrupt value", file=file,
        )  # fmt: skip
    if clip.num_frames > 1:
        speed = np.linalg.norm(np.diff(clip.root_pos, axis=0), axis=1) * clip.fps
        if float(speed.max()) > MAX_SPEED:
            frame = int(np.argmax(speed > MAX_SPEED)) + 1
            raise MotionError(
                f"frame {frame}: the root jumps at {float(speed[frame - 1]):.3g} m/s (more than "
                f"{MAX_SPEED:g} m/s): a glitch or a cut between two takes", file=file,
                hint="cut the clip at that frame",
            )  # fmt: skip
    return clip
