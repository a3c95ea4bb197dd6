"""BVH file -> canonical, floor-aligned, contact-labelled :class:`MotionClip`.

The one entry point behind the ``bvh`` motion format: parse, detect the skeleton (or use the
given name map), map onto the canonical skeleton, align the floor, label contacts, optionally
resample. Every failure is a :class:`retarget.errors.MotionError` naming the file.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from retarget.errors import MotionError
from retarget.motion import source_skeletons
from retarget.motion.bvh import BvhData, read_bvh, source_forward_kinematics
from retarget.motion.canonicalize import SourceMotion, canonicalize
from retarget.motion.clip import MotionClip
from retarget.motion.contacts import label_contacts
from retarget.motion.floor import align_floor, foot_points
from retarget.motion.plausible import check_plausible
from retarget.motion.resample import resample


def source_motion(data: BvhData) -> SourceMotion:
    pos, grot = source_forward_kinematics(data)
    return SourceMotion(
        names=data.names,
        parents=data.parents,
        positions=pos,
        rotations=grot,
        offsets=np.array([j.offset for j in data.joints]).reshape(-1, 3),
        end_sites=[j.end_site for j in data.joints],
        fps=data.fps,
    )


def clip_from_bvh(
    data: BvhData,
    *,
    name_map: Mapping[str, str | None] | None = None,
    units: str | float | None = None,
    up: str | None = None,
    fps: float | None = None,
    reference_frame: int | None = None,
    keep_source: bool = False,
) -> MotionClip:
    """Canonical clip of parsed BVH data (see module docstring)."""
    file = str(data.path) if data.path is not None else None
    label, table = source_skeletons.detect(data.names, name_map, file)
    src = source_motion(data)
    try:
        with np.errstate(all="ignore"):
            clip, info = canonicalize(
                src, table, units=units, up=up, reference_frame=reference_frame
            )
    except MotionError as exc:
        if exc.file is None:
            raise MotionError(exc.message, file=file, hint=exc.hint) from None
        raise
    if not (np.isfinite(clip.local_rot).all() and np.isfinite(clip.root_pos).all()):
        raise MotionError(
            "motion is degenerate (non-finite values after mapping; coincident joints?)", file=file
        )
    clip = align_floor(clip)
    points = foot_points(clip)
    contacts = label_contacts(points, clip.meta["foot_clearance"], clip.fps)  # type: ignore[arg-type]
    meta = dict(clip.meta)
    meta.update({k: v for k, v in info.items() if k != "source_positions" or keep_source})
    if keep_source:
        shifted = np.array(info["source_positions"], copy=True)
        shifted[..., 2] += float(meta["floor_shift"])  # type: ignore[arg-type]
        meta["source_positions"] = shifted
    path = Path(file) if file else None
    clip = clip.with_(
        contacts=contacts, skeleton=label, meta=meta, source=path, name=path.stem if path else ""
    )
    if fps is not None:
        clip = resample(clip, fps)
    return check_plausible(clip, file)


def load_bvh(path: str | Path, **options: object) -> MotionClip:
    """Read a BVH file into a canonical clip; options as :func:`clip_from_bvh`."""
    return clip_from_bvh(read_bvh(path), **options)  # type: ignore[arg-type]
