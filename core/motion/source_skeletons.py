"""Known source skeletons: which source joint plays each canonical joint.

A name map sends every canonical joint name to a source joint name, or to ``None`` when the
source has no joint there (the canonical joint then sits on its parent with a fixed rotation,
e.g. Bandai has one chest joint where the canonical spine has two). Detection picks the first
known map whose source names are all present; anything else needs a user name map, and the
error says which canonical joints were left unmapped and how to pass one.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from retarget.errors import MotionError
from retarget.motion import skeleton as sk

NameMap = Mapping[str, str | None]


def _sided(table: dict[str, str | None], left: Mapping[str, str]) -> dict[str, str | None]:
    """Complete a map from its left side: ``left`` maps a left-side source name to its right."""
    out = dict(table)
    for canon, src in list(table.items()):
        if canon.startswith("left_"):
            out["right_" + canon[5:]] = None if src is None else left[src]
    return out


CMU_3DSMAX = _sided(
    {
        "pelvis": "Hips",
        "left_hip": "LeftHip",
        "left_knee": "LeftKnee",
        "left_ankle": "LeftAnkle",
        "left_toe": "LeftToe",
        "spine": "lowerback",
        "spine1": "Chest",
        "spine2": "Chest2",
        "neck": "Neck",
        "head": "Head",
        "left_collar": "LeftCollar",
        "left_shoulder": "LeftShoulder",
        "left_elbow": "LeftElbow",
        "left_wrist": "LeftWrist",
    },
    {
        "LeftHip": "RightHip",
        "LeftKnee": "RightKnee",
        "LeftAnkle": "RightAnkle",
        "LeftToe": "RightToe",
        "LeftCollar": "RightCollar",
        "LeftShoulder": "RightShoulder",
        "LeftElbow": "RightElbow",
        "LeftWrist": "RightWrist",
    },
)
"""CMU, cgspeed "3dsMax-friendly" BVH conversion (31 joints)."""

CMU_MOTIONBUILDER = _sided(
    {
        "pelvis": "Hips",
        "left_hip": "LeftUpLeg",
        "left_knee": "LeftLeg",
        "left_ankle": "LeftFoot",
        "left_toe": "LeftToeBase",
        "spine": "LowerBack",
        "spine1": "Spine",
        "spine2": "Spine1",
        "neck": "Neck1",
        "head": "Head",
        "left_collar": "LeftShoulder",
        "left_shoulder": "LeftArm",
        "left_elbow": "LeftForeArm",
        "left_wrist": "LeftHand",
    },
    {
        "LeftUpLeg": "RightUpLeg",
        "LeftLeg": "RightLeg",
        "LeftFoot": "RightFoot",
        "LeftToeBase": "RightToeBase",
        "LeftShoulder": "RightShoulder",
        "LeftArm": "RightArm",
        "LeftForeArm": "RightForeArm",
        "LeftHand": "RightHand",
    },
)
"""CMU, cgspeed "MotionBuilder-friendly" BVH conversion (31 joints, T-pose frame 0)."""

BANDAI = _sided(
    {
        "pelvis": "Hips",
        "left_hip": "UpperLeg_L",
        "left_knee": "LowerLeg_L",
        "left_ankle": "Foot_L",
        "left_toe": "Toes_L",
        "spine": "Spine",
        "spine1": "Chest",
        "spine2": None,
        "neck": "Neck",
        "head": "Head",
        "left_collar": "Shoulder_L",
        "left_shoulder": "UpperArm_L",
        "left_elbow": "LowerArm_L",
        "left_wrist": "Hand_L",
    },
    {
        "UpperLeg_L": "UpperLeg_R",
        "LowerLeg_L": "LowerLeg_R",
        "Foot_L": "Foot_R",
        "Toes_L": "Toes_R",
        "Shoulder_L": "Shoulder_R",
        "UpperArm_L": "UpperArm_R",
        "LowerArm_L": "LowerArm_R",
        "Hand_L": "Hand_R",
    },
)
"""Bandai Namco Research Motion Dataset (22 joints incl. a dummy ``joint_Root``)."""

LAFAN1 = _sided(
    {
        "pelvis": "Hips",
        "left_hip": "LeftUpLeg",
        "left_knee": "LeftLeg",
        "left_ankle": "LeftFoot",
        "left_toe": "LeftToe",
        "spine": "Spine",
        "spine1": "Spine1",
        "spine2": "Spine2",
        "neck": "Neck",
        "head": "Head",
        "left_collar": "LeftShoulder",
        "left_shoulder": "LeftArm",
        "left_elbow": "LeftForeArm",
        "left_wrist": "LeftHand",
    },
    {
        "LeftUpLeg": "RightUpLeg",
        "LeftLeg": "RightLeg",
        "LeftFoot": "RightFoot",
        "LeftToe": "RightToe",
        "LeftShoulder": "RightShoulder",
        "LeftArm": "RightArm",
        "LeftForeArm": "RightForeArm",
        "LeftHand": "RightHand",
    },
)
"""Ubisoft LaFAN1 (22 joints, centimetres, Y up)."""

CANONICAL: dict[str, str | None] = {n: n for n in sk.JOINT_NAMES}
"""Files written by retarget itself (:mod:`retarget.motion.bvh_write`)."""

KNOWN: dict[str, NameMap] = {
    "canonical": CANONICAL,
    "cmu_3dsmax": CMU_3DSMAX,
    "cmu_motionbuilder": CMU_MOTIONBUILDER,
    "lafan1": LAFAN1,
    "bandai": BANDAI,
}
"""Detection order matters: LaFAN1 names are a subset-compatible variant of MotionBuilder's,
so the CMU MotionBuilder map (which needs ``LowerBack``/``Neck1``) is tried first."""


def _missing(name_map: NameMap, names: Sequence[str]) -> list[str]:
    present = set(names)
    return [c for c in sk.JOINT_NAMES if name_map.get(c) is not None and name_map[c] not in present]


def validate_name_map(name_map: NameMap, file: str | None = None) -> None:
    unknown = sorted(set(name_map) - set(sk.JOINT_NAMES))
    if unknown:
        raise MotionError(
            f"name map has unknown canonical joints {unknown}; canonical joints "
            f"are: {', '.join(sk.JOINT_NAMES)}",
            file=file,
        )
    absent = [c for c in sk.JOINT_NAMES if c not in name_map]
    if absent:
        raise MotionError(
            f"name map does not map canonical joints {absent}",
            file=file,
            hint="map each to a source joint name, or to null when the source "
            "has no joint there (it then rides on its parent)",
        )
    if name_map.get("pelvis") is None:
        raise MotionError("name map must map 'pelvis' to the source root joint", file=file)


def detect(
    names: Sequence[str], name_map: NameMap | None = None, file: str | None = None
) -> tuple[str, NameMap]:
    """Pick the name map for a source skeleton: the user's, else the first known that fits."""
    if name_map is not None:
        validate_name_map(name_map, file)
        missing = _missing(name_map, names)
        if missing:
            raise MotionError(
                f"name map refers to source joints that are not in the file: "
                f"{', '.join(f'{c} -> {name_map[c]}' for c in missing)}",
                file=file,
            )
        return "custom", name_map
    for label, table in KNOWN.items():
        if not _missing(table, names):
            return label, table
    best_label, best = min(KNOWN.items(), key=lambda kv: len(_missing(kv[1], names)))
    unmapped = _missing(best, names)
    raise MotionError(
        f"unknown skeleton: closest known is {best_label}, but canonical joints "
        f"{', '.join(unmapped)} have no source joint (expected "
        f"{', '.join(str(best[c]) for c in unmapped)}); source joints are: {', '.join(names)}",
        file=file,
        hint="pass a name map from canonical joint to source joint name, e.g. in the recipe "
        "`motion_formats: {bvh: {name_map: {pelvis: Hips, left_hip: LThigh, ...}}}` or "
        "BvhFormat(BvhFormat.Config(name_map={...})); canonical joints: "
        + ", ".join(sk.JOINT_NAMES),
    )
