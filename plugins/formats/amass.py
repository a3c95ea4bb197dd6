"""AMASS motion files (SMPL, SMPL-H, SMPL-X ``.npz``: ``poses``, ``trans``, ``betas``, rate)
read onto the canonical human skeleton."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Literal

from pydantic import Field

import retarget
from retarget import MotionFormat, PluginConfig

if TYPE_CHECKING:
    from retarget.motion.clip import MotionClip


class AmassConfig(PluginConfig):
    model: str | None = Field(
        None, description="your body model directory ({neutral,male,female}/model.npz, "
        "SMPL-H layout): bone lengths from each subject's betas; default: mean proportions",
    )  # fmt: skip
    up: Literal["+y", "+z"] = Field("+z", description="up axis of the files (AMASS: +z)")
    fps: float | None = Field(None, gt=0, le=1000, description="override the file's rate")


class Amass(MotionFormat[AmassConfig]):
    """AMASS archives: SMPL-family body-model parameters per frame."""

    name = "amass"
    suffixes = (".npz",)

    def accepts(self, path: Path) -> bool:
        import zipfile

        try:
            with zipfile.ZipFile(path) as archive:
                names = set(archive.namelist())
        except (OSError, zipfile.BadZipFile):
            return False
        return {"poses.npy", "trans.npy"} <= names

    def read(self, path: Path) -> MotionClip:
        from retarget.motion.import_amass import load_amass

        cfg: AmassConfig = self.config  # type: ignore[assignment]
        return load_amass(path, model=cfg.model, up=cfg.up, fps=cfg.fps)

    @classmethod
    def write_sample(cls, directory: Path) -> Path:
        """Two seconds of the generated walk as SMPL-H parameters (52 joints, 120 Hz)."""
        from retarget.motion.amass_write import write_amass
        from retarget.motion.procedural import default_motions

        walk = default_motions(names=("walk",))[0]
        directory = Path(directory)
        directory.mkdir(parents=True, exist_ok=True)
        return write_amass(walk, directory / "sample.npz", seconds=2.0)


@retarget.hookimpl
def register_motion_formats(register) -> None:
    register(Amass)
