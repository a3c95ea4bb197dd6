"""``boxes``: boxes on the floor, each placed (and randomized) on its own.

Boxes come from a preset plus an explicit list. The ``stepping_path`` preset lays four boxes
15-25 cm high across a straight walking path along +x, one every metre from x = 1 m: the
paper's stepping-over-boxes setting (Sec. 4.3, Fig. 5), where the policy has to see them in
its height map to lift its feet.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field

import retarget
from retarget.kinds import PluginConfig
from retarget.scene.props import Prop, PropScene, PropSceneConfig, box


class BoxSpec(PluginConfig):
    size: tuple[float, float, float] = Field(
        (0.4, 0.6, 0.2), description="full extents x, y, z (m)"
    )
    position: tuple[float, float] = Field((1.0, 0.0), description="centre x, y (m), scene frame")
    yaw: float = Field(0.0, description="rotation about +Z (rad)")


PRESETS: dict[str, tuple[BoxSpec, ...]] = {
    "none": (),
    "single": (BoxSpec(),),
    "stepping_path": tuple(
        BoxSpec(size=(0.4, 0.8, h), position=(1.0 + k, 0.0))
        for k, h in enumerate((0.15, 0.25, 0.10, 0.20))
    ),
}


class BoxesConfig(PropSceneConfig):
    position: tuple[float, float] = Field((0.0, 0.0), description="scene origin x, y (m)")
    yaw: float = Field(0.0, description="rotation of the whole layout about +Z (rad)")
    preset: Literal["none", "single", "stepping_path"] = Field(
        "single", description="boxes to start from: none, one box 1 m ahead, or a stepping path"
    )
    boxes: tuple[BoxSpec, ...] = Field((), description="further boxes")


class Boxes(PropScene[BoxesConfig]):
    """Boxes on the floor (a preset plus a configurable list of size, position and yaw)."""

    name = "boxes"

    def specs(self) -> tuple[BoxSpec, ...]:
        return PRESETS[self.config.preset] + tuple(self.config.boxes)

    def props(self) -> list[Prop]:
        return [
            Prop(f"box{k}", (box(b.size, (0.0, 0.0, b.size[2] / 2)),), xy=b.position, yaw=b.yaw)
            for k, b in enumerate(self.specs())
        ]


@retarget.hookimpl
def register_scenes(register) -> None:
    register(Boxes)
