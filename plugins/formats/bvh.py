"""BVH motion files (CMU in both BVH namings, Bandai Namco, LaFAN1, retarget's own, or any
skeleton given a name map) read onto the canonical human skeleton."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Literal

from pydantic import Field

import retarget
from retarget import MotionFormat, PluginConfig

if TYPE_CHECKING:
    from retarget.motion.clip import MotionClip


class BvhConfig(PluginConfig):
    name_map: dict[str, str | None] | None = Field(
        None,
        description="canonical joint -> source joint name (null: no such joint, it rides on "
        "its parent); default: detect CMU, Bandai, LaFAN1 or retarget's own naming",
    )
    units: Literal["m", "cm", "mm", "inch", "cmu"] | None = Field(
        None, description="length unit of the file; default: detected from bone lengths")
    up: Literal["+x", "-x", "+y", "-y", "+z", "-z"] | None = Field(
        None, description="up axis of the file; default: detected from the pose")
    fps: float | None = Field(
        None, gt=0, description="resample to this rate (slerp); default: keep the file's rate")
    reference_frame: int | None = Field(
        None, ge=0, description="frame on which the rest alignment is measured; default: the "
        "most upright standing frame; 0 for files whose first frame is a T-pose calibration")


class Bvh(MotionFormat[BvhConfig]):
    """Biovision hierarchy (.bvh) motion capture, mapped onto the canonical skeleton."""

    name = "bvh"
    suffixes = (".bvh",)
    cacheable = True

    def read(self, path: Path) -> MotionClip:
        from retarget.motion.import_bvh import load_bvh
        cfg: BvhConfig = self.config  # type: ignore[assignment]
        return load_bvh(path, name_map=cfg.name_map, units=cfg.units, up=cfg.up, fps=cfg.fps,
                        reference_frame=cfg.reference_frame)

    @classmethod
    def write_sample(cls, directory: Path) -> Path:
        """One second of a T-pose easing into a knee bend and an arm raise, at 30 fps."""
        import numpy as np

        from retarget.geometry import rotations as rot
        from retarget.motion import skeleton as sk
        from retarget.motion.bvh_write import write_bvh
        from retarget.motion.clip import MotionClip
        frames = 30
        t = np.linspace(0.0, 1.0, frames)
        local = rot.identity((frames, sk.NUM_JOINTS))
        bend = np.deg2rad(40.0) * t
        for side, sign in (("left", 1.0), ("right", -1.0)):
            local[:, sk.joint_index(f"{side}_hip")] = rot.from_axis_angle(
                np.array([0.0, 1.0, 0.0]), -bend)
            local[:, sk.joint_index(f"{side}_knee")] = rot.from_axis_angle(
                np.array([0.0, 1.0, 0.0]), 2 * bend)
            local[:, sk.joint_index(f"{side}_ankle")] = rot.from_axis_angle(
                np.array([0.0, 1.0, 0.0]), -bend)
            local[:, sk.joint_index(f"{side}_shoulder")] = rot.from_axis_angle(
                np.array([1.0, 0.0, 0.0]), -sign * np.deg2rad(60.0) * t)
        offsets = sk.rest_offsets()
        root = np.zeros((frames, 3))
        # keep the feet on the floor while the knees bend
        thigh, shin = -offsets[sk.joint_index("left_knee"), 2], -offsets[sk.joint_index(
            "left_ankle"), 2]
        root[:, 2] = sk.standing_pelvis_height(offsets) - (thigh + shin) * (1 - np.cos(bend))
        clip = MotionClip(30.0, root, local, offsets, name="sample")
        directory = Path(directory)
        directory.mkdir(parents=True, exist_ok=True)
        return write_bvh(clip, directory / "sample.bvh")


@retarget.hookimpl
def register_motion_formats(register) -> None:
    register(Bvh)
