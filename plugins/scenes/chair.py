"""``chair``: a dining chair of boxes (45 x 45 cm seat, top at 46 cm, backrest to 90 cm)."""

from __future__ import annotations

import retarget
from retarget.scene.props import Part, Prop, PropScene, box

SEAT = 0.45  # seat width and depth
SEAT_TOP = 0.46
SEAT_THICK = 0.04
LEG = 0.04  # square legs
BACK_TOP = 0.90
BACK_THICK = 0.04


def legs(height: float) -> tuple[Part, ...]:
    """Four square legs under the seat corners, from the floor to ``height``."""
    c = SEAT / 2 - LEG / 2
    return tuple(
        box((LEG, LEG, height), (sx * c, sy * c, height / 2)) for sx in (-1, 1) for sy in (-1, 1)
    )


def seat_and_back() -> tuple[Part, ...]:
    """The seat plate and the backrest (at -x), the parts a tilting chair moves."""
    back_h = BACK_TOP - SEAT_TOP
    return (
        box((SEAT, SEAT, SEAT_THICK), (0.0, 0.0, SEAT_TOP - SEAT_THICK / 2)),
        box((BACK_THICK, SEAT, back_h), (-SEAT / 2 + BACK_THICK / 2, 0.0, SEAT_TOP + back_h / 2)),
    )


class Chair(PropScene):
    """A dining chair: 45 x 45 cm seat with its top at 46 cm, four legs, backrest to 90 cm.

    The sitter faces +x in the chair's frame; ``position``/``yaw`` place it (default 1.2 m to
    the left of the origin, facing it) and ``randomize`` moves it per episode.
    """

    name = "chair"

    def props(self) -> list[Prop]:
        return [Prop("chair", legs(SEAT_TOP - SEAT_THICK) + seat_and_back())]


@retarget.hookimpl
def register_scenes(register) -> None:
    register(Chair)
