"""The canonical human skeleton every motion source is mapped onto.

Conventions (shared by the whole project):

* world frame: **Z up, X forward, Y left** (right-handed), metres, seconds;
* 22 joints, parents listed before children (``PARENTS[j] < j``), root ``pelvis``;
* the **T-pose** is the zero pose: every local rotation is the identity, the body faces +X,
  arms stretched sideways along +/-Y with palms down, legs straight down, feet forward. In the
  T-pose every joint frame is aligned with the world frame, so a local rotation is directly
  "how far this joint is from the T-pose" and a global rotation is the orientation of the body
  part in the world (the head's global rotation is where the face looks: +X forward);
* ``offsets[j]`` is the vector from the parent joint to joint ``j`` in the parent's frame
  (equal to its T-pose world direction times the bone length).

Readers keep the subject's own bone lengths (``MotionClip.offsets``); ``rest_offsets(height)``
gives the proportions of an average adult, used for generated motion and as the reference
directions for mapping sources.
"""

from __future__ import annotations

import numpy as np

JOINT_NAMES: tuple[str, ...] = (
    "pelvis",
    "left_hip",
    "left_knee",
    "left_ankle",
    "left_toe",
    "right_hip",
    "right_knee",
    "right_ankle",
    "right_toe",
    "spine",
    "spine1",
    "spine2",
    "neck",
    "head",
    "left_collar",
    "left_shoulder",
    "left_elbow",
    "left_wrist",
    "right_collar",
    "right_shoulder",
    "right_elbow",
    "right_wrist",
)

_PARENT_NAMES: dict[str, str | None] = {
    "pelvis": None,
    "left_hip": "pelvis",
    "left_knee": "left_hip",
    "left_ankle": "left_knee",
    "left_toe": "left_ankle",
    "right_hip": "pelvis",
    "right_knee": "right_hip",
    "right_ankle": "right_knee",
    "right_toe": "right_ankle",
    "spine": "pelvis",
    "spine1": "spine",
    "spine2": "spine1",
    "neck": "spine2",
    "head": "neck",
    "left_collar": "spine2",
    "left_shoulder": "left_collar",
    "left_elbow": "left_shoulder",
    "left_wrist": "left_elbow",
    "right_collar": "spine2",
    "right_shoulder": "right_collar",
    "right_elbow": "right_shoulder",
    "right_wrist": "right_elbow",
}

PARENTS: tuple[int, ...] = tuple(
    -1 if _PARENT_NAMES[n] is None else JOINT_NAMES.index(_PARENT_NAMES[n])  # type: ignore[arg-type]
    for n in JOINT_NAMES
)
NUM_JOINTS = len(JOINT_NAMES)
ROOT = 0

REFERENCE_HEIGHT = 1.75
"""Standing height (floor to crown) of the proportions in :data:`_REST_OFFSETS_175`."""

# T-pose offsets of a 1.75 m adult (x forward, y left, z up), parent -> joint, metres.
_REST_OFFSETS_175: dict[str, tuple[float, float, float]] = {
    "pelvis": (0.0, 0.0, 0.0),
    "left_hip": (0.0, 0.09, -0.07),
    "left_knee": (0.0, 0.0, -0.42),
    "left_ankle": (0.0, 0.0, -0.40),
    "left_toe": (0.13, 0.0, -0.05),
    "right_hip": (0.0, -0.09, -0.07),
    "right_knee": (0.0, 0.0, -0.42),
    "right_ankle": (0.0, 0.0, -0.40),
    "right_toe": (0.13, 0.0, -0.05),
    "spine": (0.0, 0.0, 0.10),
    "spine1": (0.0, 0.0, 0.12),
    "spine2": (0.0, 0.0, 0.12),
    "neck": (0.0, 0.0, 0.18),
    "head": (0.0, 0.0, 0.10),
    "left_collar": (0.0, 0.03, 0.14),
    "left_shoulder": (0.0, 0.14, 0.0),
    "left_elbow": (0.0, 0.28, 0.0),
    "left_wrist": (0.0, 0.25, 0.0),
    "right_collar": (0.0, -0.03, 0.14),
    "right_shoulder": (0.0, -0.14, 0.0),
    "right_elbow": (0.0, -0.28, 0.0),
    "right_wrist": (0.0, -0.25, 0.0),
}

ANKLE_HEIGHT_175 = 0.07
"""Ankle joint above the floor when standing (the sole is below the ankle)."""
HEAD_TOP_175 = 0.17
"""Crown of the head above the head joint (the head joint sits at the skull base, ~0.9 of
stature, where mocap skeletons put their head joint)."""

LEFT_RIGHT: tuple[int, ...] = tuple(
    JOINT_NAMES.index(n.replace("left_", "@").replace("right_", "left_").replace("@", "right_"))
    for n in JOINT_NAMES
)
"""Index of each joint's mirror partner (``left_knee`` <-> ``right_knee``; spine maps to itself)."""

FEET: tuple[int, int] = (JOINT_NAMES.index("left_ankle"), JOINT_NAMES.index("right_ankle"))
TOES: tuple[int, int] = (JOINT_NAMES.index("left_toe"), JOINT_NAMES.index("right_toe"))


def joint_index(name: str) -> int:
    """Index of a canonical joint; the error lists the valid names."""
    try:
        return JOINT_NAMES.index(name)
    except ValueError:
        raise KeyError(
            f"unknown canonical joint {name!r}; known: {', '.join(JOINT_NAMES)}"
        ) from None


def children(j: int) -> tuple[int, ...]:
    return tuple(i for i, p in enumerate(PARENTS) if p == j)


def rest_offsets(height: float = REFERENCE_HEIGHT) -> np.ndarray:
    """T-pose bone offsets ``(J, 3)`` of an average adult of the given standing height."""
    scale = height / REFERENCE_HEIGHT
    return np.array([_REST_OFFSETS_175[n] for n in JOINT_NAMES], dtype=np.float64) * scale


def tpose_positions(offsets: np.ndarray, root: np.ndarray | None = None) -> np.ndarray:
    """Joint positions ``(J, 3)`` of the T-pose with the given offsets (root at ``root``)."""
    pos = np.zeros((NUM_JOINTS, 3))
    pos[ROOT] = np.zeros(3) if root is None else root
    for j in range(1, NUM_JOINTS):
        pos[j] = pos[PARENTS[j]] + offsets[j]
    return pos


def standing_pelvis_height(offsets: np.ndarray) -> float:
    """Pelvis height above the floor when standing straight with these bone lengths."""
    pos = tpose_positions(offsets)
    scale = estimate_height(offsets) / REFERENCE_HEIGHT
    return float(-min(pos[FEET[0], 2], pos[FEET[1], 2]) + ANKLE_HEIGHT_175 * scale)


def estimate_height(offsets: np.ndarray, ankle_height: float | None = None) -> float:
    """Standing height (floor to crown) implied by a subject's bone offsets.

    Scaled from the leg: the pelvis-to-ankle span of the T-pose plus the ankle's height above
    the floor (measured on the clip when known, else the average adult's in proportion), over
    the same span of the reference proportions. The leg is used rather than the head because
    sources put their head joint at different vertebrae (Bandai's "Head" sits about 7 cm below
    the skull base, which made a head-based estimate read 1.50 m for a subject whose pelvis
    stands at 0.93 m), while hip height is a stable share of stature (~0.55).
    """
    pos = tpose_positions(offsets)
    leg = pos[ROOT, 2] - min(pos[FEET[0], 2], pos[FEET[1], 2])
    ref = tpose_positions(rest_offsets())
    ref_leg = ref[ROOT, 2] - ref[FEET[0], 2]
    if ankle_height is None:
        ankle_height = ANKLE_HEIGHT_175 * leg / ref_leg
    return float((leg + ankle_height) * REFERENCE_HEIGHT / (ref_leg + ANKLE_HEIGHT_175))
