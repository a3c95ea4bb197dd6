"""Number flags that refuse what no run can use: NaN, infinities, zero or negative counts, and
values so large they would mean hours of allocation (argparse then exits 2 with the bound)."""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable


def count(low: int = 1, high: int = 10**9) -> Callable[[str], int]:
    """An integer flag in ``[low, high]``."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"'{text}' is not a whole number") from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"{value} is outside {low}..{high}")
        return value

    parse.__name__ = "count"
    return parse


def amount(
    low: float = 0.0, high: float = 1e7, *, inclusive: bool = False
) -> Callable[[str], float]:
    """A finite number flag above ``low`` (or equal, ``inclusive``) and at most ``high``."""

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"'{text}' is not a number") from None
        if not math.isfinite(value):
            raise argparse.ArgumentTypeError(f"{text} is not finite")
        if value < low or (value == low and not inclusive) or value > high:
            side = ">=" if inclusive else ">"
            raise argparse.ArgumentTypeError(f"{value:g} must be {side} {low:g} and <= {high:g}")
        return value

    parse.__name__ = "number"
    return parse


MIN_PIXELS, MAX_PIXELS = 16, 4096
"""Picture sizes accepted (each side): an offscreen context of 0 or 100k pixels fails deep in
OpenGL."""


def image_size(text: str) -> tuple[int, int]:
    """``WIDTHxHEIGHT`` with each side in ``[MIN_PIXELS, MAX_PIXELS]``."""
    try:
        width, height = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expects WIDTHxHEIGHT, got '{text}'") from None
    for side in (width, height):
        if not MIN_PIXELS <= side <= MAX_PIXELS:
            raise argparse.ArgumentTypeError(
                f"{width}x{height}: each side is {MIN_PIXELS}..{MAX_PIXELS} pixels"
            )
    return width, height
