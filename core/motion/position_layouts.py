"""Which source joint is which canonical joint, for position-only captures.

A layout maps each canonical joint to a source joint name, or to a point *between* two source
joints (``[A, B, w]``: ``(1 - w) A + w B``) where the source has fewer joints there (a two-joint
spine). Known layouts, tried in order: the project's own names, SMPL's (AMASS exports, video
pose estimators), and Mixamo-style names (``Hips``, ``LeftUpLeg``, ``LeftForeArm``; with or
without a ``mixamorig:`` prefix; the box-climb captures use these with a two-joint spine).
``tips`` are optional extra points a layout knows (a finger base for the wrist's rotation).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from retarget.errors import MotionError
from retarget.motion import skeleton as sk

Target = str | tuple[str, str, float]

CANONICAL: dict[str, Target] = {n: n for n in sk.JOINT_NAMES}
SMPL: dict[str, Target] = {
    "pelvis": "pelvis", "left_hip": "left_hip", "left_knee": "left_knee",
    "left_ankle": "left_ankle", "left_toe": "left_foot", "right_hip": "right_hip",
    "right_knee": "right_knee", "right_ankle": "right_ankle", "right_toe": "right_foot",
    "spine": "spine1", "spine1": "spine2", "spine2": "spine3", "neck": "neck", "head": "head",
    "left_collar": "left_collar", "left_shoulder": "left_shoulder", "left_elbow": "left_elbow",
    "left_wrist": "left_wrist", "right_collar": "right_collar",
    "right_shoulder": "right_shoulder", "right_elbow": "right_elbow",
    "right_wrist": "right_wrist",
}  # fmt: skip
_MIXAMO_COMMON: dict[str, Target] = {
    "pelvis": "Hips", "neck": "Neck", "head": "Head",
    "left_collar": "LeftShoulder", "left_shoulder": "LeftArm", "left_elbow": "LeftForeArm",
    "left_wrist": "LeftHand", "right_collar": "RightShoulder", "right_shoulder": "RightArm",
    "right_elbow": "RightForeArm", "right_wrist": "RightHand",
    "left_hip": "LeftUpLeg", "left_knee": "LeftLeg", "left_ankle": "LeftFoot",
    "left_toe": "LeftToeBase", "right_hip": "RightUpLeg", "right_knee": "RightLeg",
    "right_ankle": "RightFoot", "right_toe": "RightToeBase",
}  # fmt: skip
MIXAMO: dict[str, Target] = {
    **_MIXAMO_COMMON, "spine": "Spine", "spine1": "Spine1", "spine2": "Spine2"
}
MIXAMO_SHORT_SPINE: dict[str, Target] = {
    **_MIXAMO_COMMON, "spine": "Spine", "spine1": "Spine1", "spine2": ("Spine1", "Neck", 0.5)
}
KNOWN: dict[str, dict[str, Target]] = {
    "canonical": CANONICAL,
    "smpl": SMPL,
    "mixamo": MIXAMO,
    "mixamo (two-joint spine)": MIXAMO_SHORT_SPINE,
}
TIPS: dict[str, dict[str, str]] = {
    "mixamo": {"left_hand": "LeftHandMiddle1", "right_hand": "RightHandMiddle1"},
    "mixamo (two-joint spine)": {"left_hand": "LeftHandMiddle1",
                                 "right_hand": "RightHandMiddle1"},
}  # fmt: skip


def bare(name: str) -> str:
    """A joint name without a rig prefix (``mixamorig:LeftArm`` -> ``LeftArm``)."""
    return name.rsplit(":", 1)[-1].strip()


def _sources(target: Target) -> tuple[str, ...]:
    return (target,) if isinstance(target, str) else (target[0], target[1])


def missing(layout: Mapping[str, Target], names: Sequence[str]) -> list[str]:
    have = {bare(n) for n in names}
    return [c for c in sk.JOINT_NAMES
            if c not in layout or any(s not in have for s in _sources(layout[c]))]  # fmt: skip


def parse_name_map(raw: Mapping[str, object], file: str | None) -> dict[str, Target]:
    """A user's name map: canonical joint -> source name, or ``[A, B, w]`` between two."""
    out: dict[str, Target] = {}
    for key, value in raw.items():
        if key not in sk.JOINT_NAMES:
            raise MotionError(f"name map: '{key}' is not a canonical joint (they are: "
                              f"{', '.join(sk.JOINT_NAMES)})", file=file)  # fmt: skip
        if isinstance(value, str):
            out[key] = value
        elif (isinstance(value, list | tuple) and len(value) == 3 and all(
                isinstance(v, str) for v in value[:2]) and isinstance(value[2], int | float)
                and 0 <= float(value[2]) <= 1):  # fmt: skip
            out[key] = (str(value[0]), str(value[1]), float(value[2]))
        else:
            raise MotionError(
                f"name map: '{key}' must be a source joint name or [A, B, w] with 0 <= w <= 1",
                file=file,
            )
    return out


def choose(
    names: Sequence[str], name_map: Mapping[str, Target] | None, file: str | None
) -> tuple[str, Mapping[str, Target], Mapping[str, str]]:
    """``(label, layout, tips)`` for a capture's joint ``names``: the user's map (laid over
    the best known layout, so it may name only what differs), else the first known layout
    that maps every canonical joint. Errors list the canonical joints left unmapped."""
    if name_map is not None:
        base_label, base = min(KNOWN.items(), key=lambda kv: len(missing(kv[1], names)))
        layout = {**base, **name_map}
        gaps = missing(layout, names)
        if gaps:
            raise MotionError(
                "canonical joints without a source joint: " + ", ".join(
                    f"{c} (-> {layout.get(c, 'unmapped')})" for c in gaps)
                + f"; the capture's joints are: {', '.join(names)}", file=file,
            )  # fmt: skip
        return f"custom (over {base_label})", layout, TIPS.get(base_label, {})
    for label, layout in KNOWN.items():
        if not missing(layout, names):
            return label, layout, TIPS.get(label, {})
    best_label, best = min(KNOWN.items(), key=lambda kv: len(missing(kv[1], names)))
    gaps = missing(best, names)
    raise MotionError(
        f"unknown joint layout: closest known is {best_label}, but canonical joints "
        f"{', '.join(gaps)} have no source joint; the capture's joints are: {', '.join(names)}",
        file=file,
        hint="give a name map from canonical joint to source joint (or [A, B, w] for a point "
        "between two), e.g. `--set motions.format.name_map={spine2: [Spine1, Neck, 0.5]}`",
    )
