"""Map a source skeleton's motion onto the canonical skeleton, exactly.

The recorded joint positions are the ground truth; the result must reproduce them by canonical
forward kinematics (to float precision where the source allows it). Three steps:

1. **Units and up axis** (declared, or detected): lengths are scaled to metres by the candidate
   unit that makes the subject's leg + spine length most human, and the world is rotated so that
   the axis the body stands along becomes +Z (a right-handed cyclic axis permutation, so a Y-up
   file maps x->y, y->z, z->x).
2. **Which source frame drives each canonical joint.** A canonical joint sits on its mapped
   source joint, but its rotation is taken from the source frame that carries all its canonical
   children rigidly: normally the mapped joint itself, but e.g. CMU's ``lowerneck`` (zero length,
   rotated) must drive the canonical chest or the neck would drift. Chosen numerically per clip.
3. **Rest alignment.** Rest (zero) poses of real files are not T-poses (Bandai's bones lie along
   local X; CMU 3dsMax's arms hang down), so the constant per-joint rotation from source frame to
   canonical frame is measured on a *standing reference frame* of the clip: there each canonical
   frame is built from the bone directions (swing from the T-pose direction) and the body's
   heading (twist), i.e. local rotations are relative to the canonical T-pose by construction.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from retarget.errors import MotionError
from retarget.geometry import rotations as rot
from retarget.motion import skeleton as sk
from retarget.motion.clip import MotionClip, local_from_global

UNITS: dict[str, float] = {
    "m": 1.0,
    "cm": 0.01,
    "mm": 0.001,
    "inch": 0.0254,
    "cmu": 0.0254 / 0.45,  # CMU ASF length unit, (1/0.45) inch
}
# ankle-to-head-joint chain (hip->knee->ankle + pelvis->...->head) of a 1.70 m adult
_TYPICAL_CHAIN = 1.46 * 1.70 / sk.REFERENCE_HEIGHT
RIGID_TOLERANCE = 1e-4  # metres: a frame carries a child rigidly below this spread


@dataclass
class SourceMotion:
    """A source skeleton's motion: global positions and rotations in the file's world."""

    names: list[str]
    parents: list[int]
    positions: np.ndarray  # (F, S, 3) file units
    rotations: np.ndarray  # (F, S, 4) wxyz, file world
    offsets: np.ndarray  # (S, 3) file units
    end_sites: list[np.ndarray | None]
    fps: float


def up_axis_matrix(up: str) -> np.ndarray:
    """Rotation taking a world whose up axis is ``up`` (``"+y"``, ``"-z"``, ...) to Z-up."""
    up = up.lower().strip()
    if len(up) == 1:
        up = "+" + up
    if len(up) != 2 or up[0] not in "+-" or up[1] not in "xyz":
        raise ValueError(f"up axis must be one of +x, -x, +y, -y, +z, -z; got {up!r}")
    u = "xyz".index(up[1])
    eye = np.eye(3)
    m = np.stack([eye[(u + 1) % 3], eye[(u + 2) % 3], eye[u]])
    if up[0] == "-":
        m[1:] *= -1.0
    return m


def _chain_length(src: SourceMotion, idx: dict[str, int | None]) -> float:
    """Mean length of hip->knee->ankle plus pelvis->...->head in file units."""
    p = src.positions

    def seg(a: str, b: str) -> float:
        ia, ib = idx[a], idx[b]
        if ia is None or ib is None:
            return 0.0
        return float(np.linalg.norm(p[:, ia] - p[:, ib], axis=-1).mean())

    chain = ["pelvis", "spine", "spine1", "spine2", "neck", "head"]
    total = seg("left_hip", "left_knee") + seg("left_knee", "left_ankle")
    for a, b in itertools.pairwise(chain):
        total += seg(a, b)
    return total


def detect_units(src: SourceMotion, idx: dict[str, int | None]) -> tuple[str, float]:
    """The unit whose implied leg + spine length is closest to an adult's."""
    length = _chain_length(src, idx)
    if not np.isfinite(length) or length <= 0:
        raise MotionError("cannot detect units: the skeleton has no leg/spine length")
    name = min(UNITS, key=lambda u: abs(np.log(length * UNITS[u] / _TYPICAL_CHAIN)))
    return name, UNITS[name]


def detect_up(src: SourceMotion, idx: dict[str, int | None]) -> str:
    """The world axis (with sign) along which the ankles-to-head vector points on average."""
    head = src.positions[:, idx["head"]]  # type: ignore[index]
    feet = 0.5 * (src.positions[:, idx["left_ankle"]] + src.positions[:, idx["right_ankle"]])  # type: ignore[index]
    v = (head - feet).mean(axis=0)
    axis = int(np.argmax(np.abs(v)))
    return ("+" if v[axis] >= 0 else "-") + "xyz"[axis]


def _descendant_path(parents: list[int], top: int, node: int) -> list[int]:
    """Source joints from ``top`` down to ``node`` (inclusive) or [] if not a descendant."""
    path = [node]
    while path[-1] != top:
        p = parents[path[-1]]
        if p < 0:
            return []
        path.append(p)
    return path[::-1]


def _choose_frames(
    src: SourceMotion, pos: np.ndarray, mats: np.ndarray, pos_src: list[int]
) -> list[int]:
    """Per canonical joint, the source frame that carries its canonical children rigidly."""
    frames: list[int] = []
    for j in range(sk.NUM_JOINTS):
        kids = [c for c in sk.children(j) if pos_src[c] != pos_src[j]]
        top = pos_src[j]
        if not kids:
            # leaf: the deepest zero-length descendant along first children (CMU lhand)
            best = top
            while True:
                nxt = [
                    k
                    for k, p in enumerate(src.parents)
                    if p == best and np.linalg.norm(src.offsets[k]) < 1e-9
                ]
                if not nxt:
                    break
                best = nxt[0]
            frames.append(best)
            continue
        candidates: list[int] = []
        for c in kids:
            for node in _descendant_path(src.parents, top, pos_src[c])[:-1]:
                if node not in candidates:
                    candidates.append(node)
        if not candidates:
            candidates = [top]
        spreads = []
        for f in candidates:
            worst = 0.0
            for c in kids:
                d = pos[:, pos_src[c]] - pos[:, top]
                local = np.einsum("tji,tj->ti", mats[:, f], d)
                worst = max(worst, float(np.abs(local - local.mean(0)).max()))
            spreads.append(worst)
        ok = [f for f, s in zip(candidates, spreads, strict=True) if s < RIGID_TOLERANCE]
        frames.append(ok[0] if ok else candidates[int(np.argmin(spreads))])
    return frames


def _reference_frame(pos: np.ndarray, pos_src: list[int]) -> int:
    """A standing frame: legs straight, trunk upright, pelvis slow."""

    def p(name: str) -> np.ndarray:
        return pos[:, pos_src[sk.joint_index(name)]]

    score = np.zeros(pos.shape[0])
    for side in ("left", "right"):
        thigh = p(f"{side}_knee") - p(f"{side}_hip")
        shin = p(f"{side}_ankle") - p(f"{side}_knee")
        cos = np.sum(thigh * shin, -1) / np.maximum(
            np.linalg.norm(thigh, axis=-1) * np.linalg.norm(shin, axis=-1), 1e-9
        )
        score += 1.0 - cos
    trunk = p("head") - p("pelvis")
    score += 1.0 - trunk[:, 2] / np.maximum(np.linalg.norm(trunk, axis=-1), 1e-9)
    speed = np.zeros(pos.shape[0])
    if pos.shape[0] > 1:
        speed[1:] = np.linalg.norm(np.diff(p("pelvis"), axis=0), axis=-1)
        speed[0] = speed[1] if pos.shape[0] > 1 else 0.0
    score += speed / max(float(speed.max()), 1e-9) * 0.1
    return int(np.argmin(score))


def _swing_then_heading(tdir: np.ndarray, d: np.ndarray, heading: np.ndarray) -> np.ndarray:
    """Rotation matrix R with R @ tdir = d that is closest to ``heading`` (twist from heading)."""
    s = rot.to_matrix(rot.between(heading @ tdir, d))
    return s @ heading


_LEAF_DIRECTION = {
    "head": (0.0, 0.0, 1.0),
    "left_toe": (1.0, 0.0, 0.0),
    "right_toe": (1.0, 0.0, 0.0),
    "left_wrist": (0.0, 1.0, 0.0),
    "right_wrist": (0.0, -1.0, 0.0),
}


def _reference_rotations(
    src: SourceMotion,
    pos: np.ndarray,
    mats: np.ndarray,
    pos_src: list[int],
    frames: list[int],
    t: int,
) -> np.ndarray:
    """Canonical global rotation matrices ``(J, 3, 3)`` at reference frame ``t``."""
    rest = sk.rest_offsets()
    p = pos[t]
    lhip, rhip = p[pos_src[sk.joint_index("left_hip")]], p[pos_src[sk.joint_index("right_hip")]]
    left = lhip - rhip
    left[2] = 0.0
    if np.linalg.norm(left) < 1e-9:
        raise MotionError("cannot find the body's heading: hip joints coincide")
    left /= np.linalg.norm(left)
    up = np.array([0.0, 0.0, 1.0])
    heading = np.stack([np.cross(left, up), left, up], axis=-1)
    out = np.empty((sk.NUM_JOINTS, 3, 3))
    for j, name in enumerate(sk.JOINT_NAMES):
        if name == "pelvis":
            out[j] = _swing_then_heading(np.array([0.0, 1.0, 0.0]), lhip - rhip, heading)
            continue
        # primary child: first canonical descendant (along first children) at a distance
        node, tdir, d = j, np.zeros(3), np.zeros(3)
        while sk.children(node):
            node = sk.children(node)[0]
            tdir = tdir + rest[node]
            d = p[pos_src[node]] - p[pos_src[j]]
            if np.linalg.norm(d) > 1e-3:
                break
        if np.linalg.norm(d) <= 1e-3:
            end = src.end_sites[frames[j]]
            if end is not None and np.linalg.norm(end) > 1e-9 and name in _LEAF_DIRECTION:
                tdir = np.array(_LEAF_DIRECTION[name])
                d = mats[t, frames[j]] @ end
            else:
                out[j] = out[sk.PARENTS[j]]
                continue
        out[j] = _swing_then_heading(tdir, d, heading)
    return out


def canonicalize(
    src: SourceMotion,
    name_map: Mapping[str, str | None],
    *,
    units: str | float | None = None,
    up: str | None = None,
    reference_frame: int | None = None,
) -> tuple[MotionClip, dict[str, object]]:
    """Canonical clip (not floor-aligned) plus facts about the mapping (units, up, frames)."""
    lookup = {n: i for i, n in enumerate(src.names)}
    idx: dict[str, int | None] = {}
    pos_src: list[int] = []
    for j, name in enumerate(sk.JOINT_NAMES):
        target = name_map[name]
        if target is None:
            pos_src.append(pos_src[sk.PARENTS[j]])
            idx[name] = None
        else:
            pos_src.append(lookup[target])
            idx[name] = lookup[target]
    if units is None:
        unit_name, scale = detect_units(src, idx)
    elif isinstance(units, str):
        if units not in UNITS:
            raise MotionError(f"unknown unit {units!r}; known: {', '.join(UNITS)}")
        unit_name, scale = units, UNITS[units]
    else:
        unit_name, scale = f"{units:g} m", float(units)
    up_name = detect_up(src, idx) if up is None else up
    world = up_axis_matrix(up_name)
    pos = scale * np.einsum("ij,tsj->tsi", world, src.positions)
    mats = np.einsum("ij,tsjk->tsik", world, rot.to_matrix(src.rotations))
    frames = _choose_frames(src, pos, mats, pos_src)
    if reference_frame is not None and not 0 <= reference_frame < pos.shape[0]:
        raise MotionError(
            f"reference frame {reference_frame} is outside the clip's {pos.shape[0]} frames"
        )
    t_ref = _reference_frame(pos, pos_src) if reference_frame is None else reference_frame
    ref = _reference_rotations(src, pos, mats, pos_src, frames, t_ref)
    align = np.einsum("jki,jkl->jil", mats[t_ref, frames], ref)  # C_j = R_F(t_ref)^T R_j
    gmat = np.einsum("tjik,jkl->tjil", mats[:, frames], align)
    grot = rot.from_matrix(gmat)
    local = local_from_global(grot)
    offsets = np.zeros((sk.NUM_JOINTS, 3))
    spread = np.zeros(sk.NUM_JOINTS)
    for j in range(1, sk.NUM_JOINTS):
        pj = sk.PARENTS[j]
        d = pos[:, pos_src[j]] - pos[:, pos_src[pj]]
        v = np.einsum("tki,tk->ti", gmat[:, pj], d)
        offsets[j] = v.mean(0)
        spread[j] = float(np.linalg.norm(v - offsets[j], axis=-1).max())
    clip = MotionClip(fps=src.fps, root_pos=pos[:, pos_src[0]], local_rot=local, offsets=offsets)
    info: dict[str, object] = {
        "units": unit_name,
        "unit_scale": scale,
        "up": up_name,
        "reference_frame": t_ref,
        "rotation_sources": {n: src.names[f] for n, f in zip(sk.JOINT_NAMES, frames, strict=True)},
        "max_offset_spread": float(spread.max()),
        "source_positions": pos[:, pos_src],  # metres, Z up: what canonical FK must reproduce
    }
    return clip, info
