"""``rotating_chair``: an office chair whose seat turns on a vertical revolute joint.

A 5-star base (approximated by a 60 cm disc) and a column carry a round seat with a backrest on
a damped vertical hinge: pushing a foot against the floor turns the seat, as in the paper's
rotating-chair example (Sec. 4.4). The seat's footprint is a disc, so the height map does not
depend on the seat's angle (the backrest's does, and is taken at rest).
"""

from __future__ import annotations

from pydantic import Field

import retarget
from retarget.scene.props import Hinge, Prop, PropScene, PropSceneConfig, box, cylinder

BASE_RADIUS = 0.30
BASE_THICK = 0.05
COLUMN_RADIUS = 0.03
SEAT_RADIUS = 0.25
SEAT_TOP = 0.47
SEAT_THICK = 0.06
BACK_TOP = 0.92
BACK_THICK = 0.04
BACK_WIDTH = 0.42


class RotatingChairConfig(PropSceneConfig):
    damping: float = Field(2.0, ge=0, description="N m s/rad of the swivel")
    friction: float = Field(0.5, ge=0, description="N m of dry friction of the swivel")


class RotatingChair(PropScene[RotatingChairConfig]):
    """An office chair: round 50 cm seat (top at 47 cm) and backrest on a damped swivel."""

    name = "rotating_chair"

    def props(self) -> list[Prop]:
        seat_z = SEAT_TOP - SEAT_THICK / 2
        column_top = SEAT_TOP - SEAT_THICK - 0.01
        column_h = column_top - BASE_THICK
        fixed = (
            cylinder(BASE_RADIUS, BASE_THICK, (0.0, 0.0, BASE_THICK / 2)),
            cylinder(COLUMN_RADIUS, column_h, (0.0, 0.0, BASE_THICK + column_h / 2)),
        )
        back_h = BACK_TOP - SEAT_TOP
        moving = (
            cylinder(SEAT_RADIUS, SEAT_THICK, (0.0, 0.0, seat_z)),
            box(
                (BACK_THICK, BACK_WIDTH, back_h),
                (-SEAT_RADIUS + BACK_THICK / 2, 0.0, SEAT_TOP + back_h / 2),
            ),
        )
        hinge = Hinge(
            axis=(0.0, 0.0, 1.0),
            pos=(0.0, 0.0, column_top),
            parts=moving,
            damping=self.config.damping,
            frictionloss=self.config.friction,
        )
        return [Prop("rotating_chair", fixed, hinge=hinge)]


@retarget.hookimpl
def register_scenes(register) -> None:
    register(RotatingChair)
