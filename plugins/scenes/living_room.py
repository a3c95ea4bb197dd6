"""``living_room``: the primitive scenes composed into one room.

A couch against the far wall, a stool and a chair beside it, a bench and a box on the other
side: the paper's living-room example combines objects seen in different training clips
(Sec. 4.1). Each piece keeps its own dimensions (see its module) and is randomized on its own.
"""

from __future__ import annotations

import math
from typing import Any

from pydantic import Field

import retarget
from retarget.plugins.scenes.bench import Bench
from retarget.plugins.scenes.boxes import Boxes
from retarget.plugins.scenes.chair import Chair
from retarget.plugins.scenes.couch import Couch
from retarget.plugins.scenes.stool import Stool
from retarget.scene.props import Prop, PropScene, PropSceneConfig

LAYOUT: tuple[tuple[type[PropScene[Any]], tuple[float, float], float], ...] = (
    (Couch, (0.0, 2.2), -math.pi / 2),
    (Stool, (1.4, 1.6), 0.0),
    (Chair, (-1.6, 1.4), -math.pi / 4),
    (Bench, (2.0, -1.2), math.pi),
    (Boxes, (-1.6, -1.4), 0.3),
)
"""(scene, position, yaw) of each piece in the room frame; the origin is left free."""


class LivingRoomConfig(PropSceneConfig):
    position: tuple[float, float] = Field((0.0, 0.0), description="room origin x, y (m)")
    yaw: float = Field(0.0, description="rotation of the room about +Z (rad)")


class LivingRoom(PropScene[LivingRoomConfig]):
    """A living room: couch, stool, chair, bench and a box around a free centre."""

    name = "living_room"

    def props(self) -> list[Prop]:
        out = []
        for cls, xy, yaw in LAYOUT:
            for prop in cls().props():
                out.append(prop.moved(xy, yaw))
        names: dict[str, int] = {}
        for i, prop in enumerate(out):  # unique body names when a scene repeats a prop name
            k = names.get(prop.name, 0)
            names[prop.name] = k + 1
            if k:
                out[i] = Prop(f"{prop.name}{k}", prop.parts, prop.xy, prop.yaw, prop.hinge)
        return out


@retarget.hookimpl
def register_scenes(register) -> None:
    register(LivingRoom)
