"""Elbows as hinges: the same body, its arm rotations split the way a hinged elbow can follow.

A mocap elbow is a ball joint: the file puts part of the forearm's direction in the elbow's
own twist and sideways swing, and sources disagree on how much (Bandai Namco's elbows swing
the forearm well off the flexion plane; other files leave it in the shoulder). A character's
elbow is a hinge, and the joint map drives it by the bend angle alone
(:func:`retarget.character.joint_map.elbow_link`), so whatever else the file's elbow did is
lost: the forearm bends in the wrong plane, and the character's hands land 12 cm (walks) to
28-33 cm (runs, arm waves) from the controllers the person held, although the body was copied
joint for joint.

This rewrites each frame's shoulder, elbow and wrist rotations so that the elbow is exactly a
hinge about its flexion axis by the same bend, the upper arm is twisted about its own bone so
that the forearm lies where it was, and the wrist takes what is left, so the hand keeps its
orientation: every joint's global position and rotation is unchanged (on the canonical
T-pose, whose arms are straight along the bone axis) wherever the elbow bends 20 degrees or
more, only the split between joints moves; a nearly straight arm keeps its twist where it was.
A character retargeted from the rewritten clip bends its forearm where the person's went.
Vectorised over frames; no fitting.
"""

from __future__ import annotations

import numpy as np

from retarget.geometry import rotations as rot
from retarget.motion import skeleton as sk
from retarget.motion.clip import MotionClip

ARMS: tuple[tuple[str, tuple[float, float, float], tuple[float, float, float]], ...] = (
    ("left", (0.0, 1.0, 0.0), (0.0, 0.0, -1.0)),
    ("right", (0.0, -1.0, 0.0), (0.0, 0.0, 1.0)),
)
"""Per arm: side, the bone axis in the T-pose (along the arm) and the flexion axis (the
forearm bends forward), in the canonical frame (X forward, Y left, Z up)."""
FULL_TWIST_BEND = 0.35
"""Radians of bend (20 degrees) from which the forearm's direction is kept exactly; below it
the twist fades to none at a straight arm, whose bending plane is undefined (a file's 2-degree
sideways bend would otherwise turn the upper arm 90 degrees about itself)."""


def hinge_split(
    shoulder: np.ndarray, elbow: np.ndarray, wrist: np.ndarray,
    bone: np.ndarray, flex: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """Local rotations ``(..., 4)`` of one arm rewritten so the elbow turns about ``flex``
    only; the composed rotation at the wrist is unchanged, and so is the forearm's direction
    wherever the elbow bends :data:`FULL_TWIST_BEND` or more."""
    shape = (*elbow.shape[:-1], 3)
    b = np.broadcast_to(np.asarray(bone, dtype=np.float64), shape)
    f = np.broadcast_to(np.asarray(flex, dtype=np.float64), shape)
    forearm = rot.apply(elbow, b)  # where the forearm points in the upper arm's frame
    bend = np.arccos(np.clip((forearm * b).sum(-1), -1.0, 1.0))
    bent = rot.apply(rot.from_axis_angle(f, bend), b)  # the same bend in the flexion plane
    # the twist about the bone that turns ``bent`` onto ``forearm`` (both at ``bend`` from it)
    sin = (np.cross(bent, forearm) * b).sum(-1)
    cos = (bent * forearm).sum(-1) - (bent * b).sum(-1) * (forearm * b).sum(-1)
    turn = np.arctan2(sin, cos)
    # a forearm bent backwards (hyperextended) is a negative hinge angle, not half a turn of
    # the upper arm; near a straight arm the bending plane is noise, so the twist fades out
    back = np.abs(turn) > np.pi / 2
    bend = np.where(back, -bend, bend)
    turn = np.where(back, turn - np.pi * np.sign(turn), turn)
    fade = np.clip(np.abs(bend) / FULL_TWIST_BEND, 0.0, 1.0)
    turn = turn * fade * fade * (3.0 - 2.0 * fade)
    hinge = rot.from_axis_angle(f, bend)
    twist = rot.from_axis_angle(b, turn)
    left_over = rot.mul(rot.conj(rot.mul(twist, hinge)), elbow)  # identity when hinged
    return (rot.normalize(rot.mul(shoulder, twist)), rot.normalize(hinge),
            rot.normalize(rot.mul(left_over, wrist)))  # fmt: skip


def hinge_elbows(clip: MotionClip) -> MotionClip:
    """``clip`` with both elbows as hinges (:func:`hinge_split`); its global pose unchanged."""
    local = clip.local_rot.copy()
    for side, bone, flex in ARMS:
        s, e, w = (sk.joint_index(f"{side}_{j}") for j in ("shoulder", "elbow", "wrist"))
        local[:, s], local[:, e], local[:, w] = hinge_split(
            local[:, s], local[:, e], local[:, w], np.asarray(bone), np.asarray(flex)
        )
    return clip.with_(local_rot=local)
