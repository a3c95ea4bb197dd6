"""Writing canonical clips as BVH (samples, round-trip tests, export to other tools).

Files are written the way most tools expect (Y up, centimetres, ``ZXY`` channels), with the
canonical joint names. ``frame_rotations`` gives each joint's file frame relative to its
canonical frame, so tests can write the same motion with any rest pose (e.g. bones along local
X like Bandai's) and check that reading it back recovers the T-pose-relative rotations.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from retarget.geometry import rotations as rot
from retarget.motion import skeleton as sk
from retarget.motion.canonicalize import UNITS, up_axis_matrix
from retarget.motion.clip import MotionClip

_END_SITES = {
    "head": (0.0, 0.0, 0.12),
    "left_toe": (0.05, 0.0, 0.0),
    "right_toe": (0.05, 0.0, 0.0),
    "left_wrist": (0.0, 0.08, 0.0),
    "right_wrist": (0.0, -0.08, 0.0),
}


def write_bvh(
    clip: MotionClip,
    path: str | Path,
    *,
    frame_rotations: np.ndarray | None = None,
    up: str = "+y",
    units: str = "cm",
    order: str = "zxy",
) -> Path:
    """Write ``clip`` to ``path`` as BVH and return the path."""
    path = Path(path)
    a = (
        rot.identity((sk.NUM_JOINTS,))
        if frame_rotations is None
        else rot.normalize(frame_rotations)
    )
    to_file = up_axis_matrix(up).T  # canonical world -> file world
    to_file_q = rot.from_matrix(to_file)
    scale = 1.0 / UNITS[units]
    parents = np.array(sk.PARENTS)
    local = np.empty_like(clip.local_rot)
    local[:, 0] = rot.mul(rot.mul(to_file_q, clip.local_rot[:, 0]), a[0])
    local[:, 1:] = rot.mul(rot.mul(rot.conj(a[parents[1:]]), clip.local_rot[:, 1:]), a[1:])
    euler = rot.to_euler(local, order)  # (T, J, 3)
    root = clip.root_pos @ to_file.T * scale
    names = "".join(f"{c.upper()}rotation " for c in order).strip()
    lines = ["HIERARCHY"]

    def emit(j: int, depth: int) -> None:
        pad = "  " * depth
        if j == 0:
            offset = np.zeros(3)
            lines.append(f"{pad}ROOT {sk.JOINT_NAMES[j]}")
        else:
            offset = rot.apply(rot.conj(a[sk.PARENTS[j]]), clip.offsets[j]) * scale
            lines.append(f"{pad}JOINT {sk.JOINT_NAMES[j]}")
        lines.append(f"{pad}{{")
        lines.append(f"{pad}  OFFSET {offset[0]:.6f} {offset[1]:.6f} {offset[2]:.6f}")
        if j == 0:
            lines.append(f"{pad}  CHANNELS 6 Xposition Yposition Zposition {names}")
        else:
            lines.append(f"{pad}  CHANNELS 3 {names}")
        kids = sk.children(j)
        for c in kids:
            emit(c, depth + 1)
        if not kids:
            end = (
                rot.apply(
                    rot.conj(a[j]), np.array(_END_SITES.get(sk.JOINT_NAMES[j], (0.0, 0.0, 0.0)))
                )
                * scale
            )
            lines.append(f"{pad}  End Site")
            lines.append(f"{pad}  {{")
            lines.append(f"{pad}    OFFSET {end[0]:.6f} {end[1]:.6f} {end[2]:.6f}")
            lines.append(f"{pad}  }}")
        lines.append(f"{pad}}}")

    emit(0, 0)
    lines.append("MOTION")
    lines.append(f"Frames: {clip.num_frames}")
    lines.append(f"Frame Time: {1.0 / clip.fps:.8f}")
    values = np.concatenate([root, euler.reshape(clip.num_frames, -1)], axis=1)
    body = "\n".join(" ".join(f"{v:.6f}" for v in row) for row in values)
    path.write_text("\n".join(lines) + "\n" + body + "\n")
    return path
