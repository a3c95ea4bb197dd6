"""``couch``: a three-seat couch of boxes (200 x 90 cm, seat at 42 cm, backrest to 85 cm)."""

from __future__ import annotations

import retarget
from retarget.scene.props import Prop, PropScene, box

WIDTH = 2.0  # along y
DEPTH = 0.9  # along x, front at +x
SEAT_TOP = 0.42
BACK_TOP = 0.85
BACK_THICK = 0.2
ARM_TOP = 0.60
ARM_WIDTH = 0.2


class Couch(PropScene):
    """A couch: 200 cm wide and 90 cm deep, seat top at 42 cm, backrest to 85 cm (20 cm thick)
    and armrests to 60 cm (20 cm wide); the sitter faces +x."""

    name = "couch"

    def props(self) -> list[Prop]:
        seat_depth = DEPTH - BACK_THICK
        seat_x = -DEPTH / 2 + BACK_THICK + seat_depth / 2
        arm_y = WIDTH / 2 - ARM_WIDTH / 2
        parts = (
            box((BACK_THICK, WIDTH, BACK_TOP), (-DEPTH / 2 + BACK_THICK / 2, 0.0, BACK_TOP / 2)),
            box((seat_depth, WIDTH - 2 * ARM_WIDTH, SEAT_TOP), (seat_x, 0.0, SEAT_TOP / 2)),
            box((seat_depth, ARM_WIDTH, ARM_TOP), (seat_x, arm_y, ARM_TOP / 2)),
            box((seat_depth, ARM_WIDTH, ARM_TOP), (seat_x, -arm_y, ARM_TOP / 2)),
        )
        return [Prop("couch", parts)]


@retarget.hookimpl
def register_scenes(register) -> None:
    register(Couch)
