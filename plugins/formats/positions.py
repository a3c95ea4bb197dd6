"""Position-only captures (``.npy``/``.npz``: frames x joints x 3 global positions) read onto
the canonical skeleton, rotations fitted from bone directions."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Literal

from pydantic import Field

import retarget
from retarget import MotionFormat, PluginConfig

if TYPE_CHECKING:
    from retarget.motion.clip import MotionClip


class PositionsConfig(PluginConfig):
    joints: str | list[str] | None = Field(
        None, description="joint names in array order: a text file (one name per line) or a "
        "list; a .npz may carry its own 'joints'",
    )  # fmt: skip
    fps: float | None = Field(None, gt=0, le=1000, description="frame rate of the capture, Hz")
    name_map: dict[str, str | tuple[str, str, float]] | None = Field(
        None, description="canonical joint -> source joint, or [A, B, w] for a point between "
        "two; laid over the closest known layout (canonical, SMPL, Mixamo-style)",
    )  # fmt: skip
    units: Literal["m", "cm", "mm", "inch"] = Field("m", description="length unit of the file")
    up: Literal["+x", "-x", "+y", "-y", "+z", "-z"] = Field("+z", description="up axis")


class Positions(MotionFormat[PositionsConfig]):
    """Global joint positions only (markerless capture, video pose, mocap exports)."""

    name = "positions"
    suffixes = (".npy", ".npz")

    def accepts(self, path: Path) -> bool:
        if path.suffix.lower() != ".npz":
            return True
        import zipfile

        try:
            with zipfile.ZipFile(path) as archive:
                return "positions.npy" in archive.namelist()
        except (OSError, zipfile.BadZipFile):
            return False

    def read(self, path: Path) -> MotionClip:
        from retarget.motion.import_positions import load_positions, read_joint_names
        from retarget.motion.position_layouts import parse_name_map

        cfg: PositionsConfig = self.config  # type: ignore[assignment]
        joints = read_joint_names(cfg.joints) if isinstance(cfg.joints, str) else cfg.joints
        name_map = parse_name_map(cfg.name_map, str(path)) if cfg.name_map else None
        return load_positions(path, joints=joints, fps=cfg.fps, name_map=name_map,
                              units=cfg.units, up=cfg.up)  # fmt: skip

    @classmethod
    def write_sample(cls, directory: Path) -> Path:
        """Two seconds of the generated walk as canonical joint positions, names and rate
        inside (a self-describing .npz)."""
        import numpy as np

        from retarget.motion import skeleton as sk
        from retarget.motion.procedural import default_motions

        walk = default_motions(names=("walk",))[0]
        count = int(2 * walk.fps)
        directory = Path(directory)
        directory.mkdir(parents=True, exist_ok=True)
        path = directory / "sample.npz"
        np.savez(path, positions=walk.global_pos[:count].astype(np.float32),
                 joints=np.array(sk.JOINT_NAMES), fps=np.array(walk.fps))  # fmt: skip
        return path


@retarget.hookimpl
def register_motion_formats(register) -> None:
    register(Positions)
