"""``bench``: a 120 x 35 cm bench, seat top at 45 cm, on two slab legs."""

from __future__ import annotations

import retarget
from retarget.scene.props import Prop, PropScene, box

LENGTH = 1.2  # along y: people sit side by side
DEPTH = 0.35
SEAT_TOP = 0.45
SEAT_THICK = 0.05
SLAB = 0.05


class Bench(PropScene):
    """A backless bench: a 120 cm long, 35 cm deep seat (top at 45 cm) on two slab legs."""

    name = "bench"

    def props(self) -> list[Prop]:
        leg_h = SEAT_TOP - SEAT_THICK
        legs = tuple(
            box((DEPTH, SLAB, leg_h), (0.0, sy * (LENGTH / 2 - 0.1), leg_h / 2)) for sy in (-1, 1)
        )
        seat = box((DEPTH, LENGTH, SEAT_THICK), (0.0, 0.0, SEAT_TOP - SEAT_THICK / 2))
        return [Prop("bench", (*legs, seat))]


@retarget.hookimpl
def register_scenes(register) -> None:
    register(Bench)
