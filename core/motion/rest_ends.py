"""Starting from and stopping to a standstill, made from clips that start and end moving.

Motion-capture takes of locomotion are usually cut mid-stride: not one walk, turn or run of the
Bandai Namco corpus starts or ends below 0.2 m/s. A policy trained on them has never seen a
person set off from standing still or come to a stop, and a live user does both all the time:
the avatar stands while the headset walks away, then falls reaching for it. This module makes
those two moments from the clips themselves, by time-warping each end of a moving clip: the
pose of a nearby double-support frame (both feet down, a pose a person can stand in) is held
still, then the clip's own time runs from 0 to full speed along a smoothstep, so every frame
is a real pose of the take, only its timing changes.

Only ends with both feet down within ``window`` seconds are warped (a run's flight phases
have none), so what comes out is a stance that can be held; a clip whose end does not move
is left alone.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from retarget.motion.clip import MotionClip
from retarget.motion.resample import at_frames


@dataclass(frozen=True)
class RestEnds:
    """How the start and stop variants are made (seconds; metres per second)."""

    hold: float = 0.5  # standing still before setting off / after stopping
    ramp: float = 1.0  # from standstill to the take's own speed (smoothstep)
    keep: float = 2.0  # of the take at full speed after the ramp (before, for a stop)
    min_speed: float = 0.3  # mean root speed over ``window`` that counts as moving
    window: float = 0.6  # where a double-support frame is looked for, from each end

    def __post_init__(self) -> None:
        for name in ("hold", "ramp", "keep", "window"):
            if not 0.0 <= getattr(self, name) <= 60.0:
                raise ValueError(f"RestEnds.{name} must be within [0, 60] s")
        if self.ramp <= 0 or self.window <= 0:
            raise ValueError("RestEnds.ramp and RestEnds.window must be positive")


def warp_profile(fps: float, ends: RestEnds) -> np.ndarray:
    """Seconds of the take played by each output frame of a start: ``hold`` at 0, then the
    integral of a smoothstep rate over ``ramp`` (``ramp / 2`` of the take), then ``keep`` more."""
    total = ends.hold + ends.ramp + ends.keep
    t = np.arange(int(np.floor(total * fps + 1e-9)) + 1) / fps
    x = np.clip((t - ends.hold) / ends.ramp, 0.0, 1.0)
    ramped = ends.ramp * (x**3 - 0.5 * x**4)  # integral of 3x^2 - 2x^3
    after = np.clip(t - ends.hold - ends.ramp, 0.0, None)
    return ramped + after


def root_speed(clip: MotionClip) -> np.ndarray:
    """Horizontal root speed per frame ``(T,)``, m/s (the last frame repeats its neighbour)."""
    if clip.num_frames < 2:
        return np.zeros(clip.num_frames)
    v = np.linalg.norm(np.diff(clip.root_pos[:, :2], axis=0), axis=1) * clip.fps
    return np.append(v, v[-1])


def rest_ends(clip: MotionClip, ends: RestEnds | None = None) -> list[MotionClip]:
    """Up to two new clips: ``NAME_from_rest`` (stands, then sets off into the take) and
    ``NAME_to_rest`` (the take's end slowed to a stop, then standing). Empty when neither end
    of the clip moves or has both feet down nearby."""
    ends = ends or RestEnds()
    n, fps = clip.num_frames, clip.fps
    w = max(round(ends.window * fps), 1)
    if n < 2 * w:
        return []
    speed = root_speed(clip)
    both = np.asarray(clip.contacts).all(axis=1)
    profile = warp_profile(fps, ends) * fps  # in frames of the take
    out: list[MotionClip] = []
    down = np.flatnonzero(both[:w])
    if speed[:w].mean() >= ends.min_speed and down.size:
        first = int(down[0])
        src = first + profile
        if src[-1] <= n - 1:
            out.append(_named(at_frames(clip, src), clip, "from_rest"))
    down = np.flatnonzero(both[n - w:])
    if speed[n - w:].mean() >= ends.min_speed and down.size:
        last = n - w + int(down[-1])
        src = last - profile[::-1]
        if src[0] >= 0:
            out.append(_named(at_frames(clip, src), clip, "to_rest"))
    return out


def with_rest_ends(clips: list[MotionClip], ends: RestEnds | None = None) -> list[MotionClip]:
    """``clips`` followed by the start and stop variants of every clip that has them."""
    return list(clips) + [v for c in clips for v in rest_ends(c, ends)]


def _named(made: MotionClip, source: MotionClip, suffix: str) -> MotionClip:
    return made.with_(name=f"{source.name}_{suffix}" if source.name else suffix,
                      meta={**source.meta, "rest_end": suffix})  # fmt: skip
