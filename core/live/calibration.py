"""Where the user's room sits in the character's world: a turn about +Z and a horizontal shift.

As a VR application calibrates its avatar, the first headset pose is moved to where the
character starts (heights are kept: they are the user's real heights); the same rigid motion
maps every later sample in, and its inverse maps the character back into the user's room. A run
whose devices are at the character's size (``env.devices: character``) also scales the room
about the floor under the first headset by the character's size over the user's
(:func:`retarget.motion.device_stream.height_scale`); the way out undoes it, so the avatar
stands where the user stands.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from retarget.geometry import rotations as rot
from retarget.motion.device_stream import height_scale, move_poses


@dataclass(frozen=True)
class Calibration:
    yaw: float  # radians, room -> world
    origin: np.ndarray  # (2,) room xy that maps to ``target``
    target: np.ndarray  # (2,) world xy
    scale: float = 1.0  # world lengths per room length

    @classmethod
    def between(
        cls, first_headset: np.ndarray, start_headset: np.ndarray, *, scale: bool = False
    ) -> Calibration:
        """The motion taking ``first_headset`` (7,) to ``start_headset``'s place and heading
        (and, with ``scale``, height)."""
        yaw = float(rot.yaw(start_headset[3:]) - rot.yaw(first_headset[3:]))
        k = height_scale(first_headset, start_headset) if scale else 1.0
        return cls(yaw, np.asarray(first_headset[:2], float), np.asarray(start_headset[:2], float),
                   k)  # fmt: skip

    def to_world(self, poses: np.ndarray) -> np.ndarray:
        """Room poses ``(..., 7)`` into the character's world."""
        return move_poses(poses, self.yaw, self.origin, self.target, self.scale)

    def to_room(self, poses: np.ndarray) -> np.ndarray:
        """World poses ``(..., 7)`` back into the user's room."""
        return move_poses(poses, -self.yaw, self.target, self.origin, 1.0 / self.scale)
