"""Foot-contact labels from sole height and foot speed.

A foot is in contact when its lowest sole point (see :mod:`retarget.motion.floor`) is below
``height`` and its slowest sole point (heel, ball or tip) moves slower than ``speed``: heel
strike and toe-off both count, a swinging foot skimming the floor does not.

The paper's thresholds are 0.2 m and 0.4 m/s, the height measured at the joints. Measured on
sole points, 0.2 m is no constraint at all for walking (a swinging sole stays below 0.1 m), so
the height here is 0.05 m at the sole (about 0.1-0.15 m at the ankle joint) and the speed stays
0.4 m/s. On the shared clips this gives 0.50-0.61 per foot on the Bandai walks (0.05-0.20 of the
frames in double support), 0.2-0.3 on runs (no double support) and 1.0 when standing; raising
the height to 0.2 m changes none of the walking ratios by more than 0.01, the speed decides.
"""

from __future__ import annotations

import numpy as np

HEIGHT_THRESHOLD = 0.05  # metres above the floor, at the sole
SPEED_THRESHOLD = 0.4  # metres per second


def foot_speeds(points: np.ndarray, fps: float) -> np.ndarray:
    """Per frame and foot, the speed of its slowest sole point ``(T, 2)``."""
    if points.shape[0] < 2:
        return np.zeros((points.shape[0], 2))
    v = np.gradient(points, axis=0) * fps
    return np.linalg.norm(v, axis=-1).min(axis=1)


def label_contacts(
    points: np.ndarray,
    clearance: np.ndarray,
    fps: float,
    *,
    height: float = HEIGHT_THRESHOLD,
    speed: float = SPEED_THRESHOLD,
) -> np.ndarray:
    """Boolean contacts ``(T, 2)`` (left, right) from sole points ``(T, 3, 2, 3)``."""
    from retarget.motion.floor import sole_heights

    return (sole_heights(points, clearance) < height) & (foot_speeds(points, fps) < speed)
