"""Where a motion says props must be: a seat under a sitting pelvis, boxes under raised feet.

QuestEnvSim's clips come with measured object placements. Clips without them still imply some:

* **Seats**: the pelvis is *low* (below ``LOW_FRACTION`` of its standing height) and *still*
  (slower than ``STILL_SPEED``) for at least ``MIN_SECONDS``. The seat top is ``SEAT_DROP``
  below the median pelvis joint over that stretch (the hip joint centres sit about 9 cm above
  the ischial tuberosities that rest on a seat, for a 1.75 m adult; scaled by the subject's
  height), centred under the pelvis and turned to its heading.
* **Boxes**: a foot *rests* (its slowest sole point slower than the contact labels' 0.4 m/s)
  with its lowest sole point above ``BOX_MIN_HEIGHT`` for at least ``BOX_MIN_SECONDS``. The box
  top is the median sole height there, centred under the foot (heel to ball) and turned to
  its heading. Boxes of the two feet at the same height close together merge into one.

Heights are above the clip's floor (z = 0 after floor alignment). Everything here is per clip
and pure numpy: it runs once, before the world is built.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from retarget.geometry import rotations as rot
from retarget.motion import skeleton as sk
from retarget.motion.clip import MotionClip
from retarget.motion.contacts import SPEED_THRESHOLD, foot_speeds
from retarget.motion.floor import clearances, foot_points, sole_heights

LOW_FRACTION = 0.8
STILL_SPEED = 0.15  # m/s of the pelvis
MIN_SECONDS = 0.5
SEAT_DROP = 0.09  # m below the pelvis joint, for a 1.75 m adult
SEAT_SIZE = (0.45, 0.45)  # m, depth x width
BOX_MIN_HEIGHT = 0.05  # m: the contact labels' sole height threshold
BOX_MIN_SECONDS = 0.3
BOX_SIZE = (0.4, 0.3)  # m, along x width of the foot
MERGE_DISTANCE = 0.35  # m between two boxes' centres that merge
MERGE_HEIGHT = 0.03  # m between two boxes' tops that merge


@dataclass(frozen=True)
class FittedProp:
    """A box standing on the floor: ``kind`` says why it is there."""

    kind: Literal["seat", "box"]
    position: tuple[float, float]  # world x, y of its centre
    yaw: float  # radians about +Z
    height: float  # its top above the floor, metres
    size: tuple[float, float]  # x, y extents in its own frame, metres


def _runs(mask: np.ndarray, min_frames: int) -> list[tuple[int, int]]:
    """``[start, end)`` of the runs of True at least ``min_frames`` long."""
    edges = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    starts, ends = np.nonzero(edges == 1)[0], np.nonzero(edges == -1)[0]
    return [(int(a), int(b)) for a, b in zip(starts, ends, strict=True) if b - a >= min_frames]


def _heading(quats: np.ndarray) -> float:
    """Mean heading (yaw of the rotated +x axis) of orientations ``(T, 4)``."""
    fwd = rot.apply(quats, np.array([1.0, 0.0, 0.0]))
    return float(np.arctan2(fwd[:, 1].mean(), fwd[:, 0].mean()))


def fit_seats(clip: MotionClip) -> list[FittedProp]:
    """A seat under each stretch where the pelvis is low and still (see the module doc)."""
    pelvis = clip.global_pos[:, sk.joint_index("pelvis")]
    standing = sk.standing_pelvis_height(clip.offsets)
    speed = np.linalg.norm(np.gradient(pelvis, axis=0), axis=-1) * clip.fps
    sitting = (pelvis[:, 2] < LOW_FRACTION * standing) & (speed < STILL_SPEED)
    scale = clip.height / sk.REFERENCE_HEIGHT
    seats = []
    for a, b in _runs(sitting, max(1, round(MIN_SECONDS * clip.fps))):
        xy = np.median(pelvis[a:b, :2], axis=0)
        top = float(np.median(pelvis[a:b, 2])) - SEAT_DROP * scale
        yaw = _heading(clip.global_rot[a:b, sk.joint_index("pelvis")])
        seats.append(FittedProp("seat", (float(xy[0]), float(xy[1])), yaw, top, SEAT_SIZE))
    return seats


def fit_boxes(clip: MotionClip) -> list[FittedProp]:
    """A box under each stretch where a foot rests above the floor (see the module doc)."""
    points = foot_points(clip)  # (T, 3, 2, 3): heel, ball, tip per foot
    heights = sole_heights(points, clearances(points))  # (T, 2)
    resting = foot_speeds(points, clip.fps) < SPEED_THRESHOLD
    boxes: list[FittedProp] = []
    for foot in range(2):
        raised = resting[:, foot] & (heights[:, foot] > BOX_MIN_HEIGHT)
        for a, b in _runs(raised, max(1, round(BOX_MIN_SECONDS * clip.fps))):
            xy = points[a:b, :2, foot, :2].mean(axis=(0, 1))  # between heel and ball
            top = float(np.median(heights[a:b, foot]))
            yaw = _heading(clip.global_rot[a:b, sk.TOES[foot]])
            boxes.append(FittedProp("box", (float(xy[0]), float(xy[1])), yaw, top, BOX_SIZE))
    return _merge(boxes)


def _merge(boxes: list[FittedProp]) -> list[FittedProp]:
    """Boxes close together at the same height become one covering both."""
    out: list[FittedProp] = []
    for box in boxes:
        for i, other in enumerate(out):
            gap = np.hypot(box.position[0] - other.position[0], box.position[1] - other.position[1])
            if gap < MERGE_DISTANCE and abs(box.height - other.height) < MERGE_HEIGHT:
                x = (box.position[0] + other.position[0]) / 2
                y = (box.position[1] + other.position[1]) / 2
                size = (max(box.size[0], other.size[0]), max(box.size[1], other.size[1]) + gap)
                out[i] = FittedProp("box", (x, y), other.yaw, max(box.height, other.height), size)
                break
        else:
            out.append(box)
    return out


def fit_props(clip: MotionClip) -> list[FittedProp]:
    """Seats and boxes a clip implies."""
    return fit_seats(clip) + fit_boxes(clip)
