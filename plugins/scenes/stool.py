"""``stool``: a round four-legged stool (34 cm seat, top at 45 cm)."""

from __future__ import annotations

import math

import retarget
from retarget.scene.props import Prop, PropScene, cylinder

RADIUS = 0.17
SEAT_TOP = 0.45
SEAT_THICK = 0.04
LEG_RADIUS = 0.015
LEG_CIRCLE = 0.12  # legs stand on this circle


class Stool(PropScene):
    """A round stool: a 34 cm seat disc with its top at 45 cm on four thin cylindrical legs."""

    name = "stool"

    def props(self) -> list[Prop]:
        leg_h = SEAT_TOP - SEAT_THICK
        legs = tuple(
            cylinder(
                LEG_RADIUS,
                leg_h,
                (LEG_CIRCLE * math.cos(a), LEG_CIRCLE * math.sin(a), leg_h / 2),
            )
            for a in (math.pi / 4 + k * math.pi / 2 for k in range(4))
        )
        seat = cylinder(RADIUS, SEAT_THICK, (0.0, 0.0, SEAT_TOP - SEAT_THICK / 2))
        return [Prop("stool", (*legs, seat))]


@retarget.hookimpl
def register_scenes(register) -> None:
    register(Stool)
