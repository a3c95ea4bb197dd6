"""``tilting_chair``: the chair with seat and backrest on a spring-damper hinge.

The hinge runs across the chair (axis y) at the top of the legs, so leaning back tilts the seat
and backrest backwards against the spring, as in the paper's tilting-chair example (Sec. 4.4).
"""

from __future__ import annotations

from pydantic import Field

import retarget
from retarget.plugins.scenes.chair import SEAT_THICK, SEAT_TOP, legs, seat_and_back
from retarget.scene.props import Hinge, Prop, PropScene, PropSceneConfig


class TiltingChairConfig(PropSceneConfig):
    stiffness: float = Field(
        400.0, ge=0, description="N m/rad: a 70 kg sitter 10 cm behind the hinge tilts ~0.17 rad"
    )
    damping: float = Field(40.0, ge=0, description="N m s/rad")
    max_tilt: float = Field(0.35, gt=0, description="hinge limit either way, radians")


class TiltingChair(PropScene[TiltingChairConfig]):
    """A dining chair whose seat and backrest tilt on a hinge with a spring-damper."""

    name = "tilting_chair"

    def props(self) -> list[Prop]:
        cfg = self.config
        hinge_z = SEAT_TOP - SEAT_THICK
        hinge = Hinge(
            axis=(0.0, 1.0, 0.0),
            pos=(0.0, 0.0, hinge_z),
            parts=seat_and_back(),
            stiffness=cfg.stiffness,
            damping=cfg.damping,
            range=(-cfg.max_tilt, cfg.max_tilt),
        )
        return [Prop("tilting_chair", legs(hinge_z - 0.01), hinge=hinge)]


@retarget.hookimpl
def register_scenes(register) -> None:
    register(TiltingChair)
