"""Where the user's room sits in the character's world: a turn about +Z and a horizontal shift.

As a VR application calibrates its avatar, the first headset pose is moved to where the
character starts (heights are kept: they are the user's real heights); the same rigid motion
maps every later sample in, and its inverse maps the character back into the user's room.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from retarget.geometry import rotations as rot


@dataclass(frozen=True)
class Calibration:
    yaw: float  # radians, room -> world
    origin: np.ndarray  # (2,) room xy that maps to ``target``
    target: np.ndarray  # (2,) world xy

    @classmethod
    def between(cls, first_headset: np.ndarray, start_headset: np.ndarray) -> Calibration:
        """The motion taking ``first_headset`` (7,) to ``start_headset``'s place and heading."""
        yaw = float(rot.yaw(start_headset[3:]) - rot.yaw(first_headset[3:]))
        return cls(yaw, np.asarray(first_headset[:2], float), np.asarray(start_headset[:2], float))

    def to_world(self, poses: np.ndarray) -> np.ndarray:
        """Room poses ``(..., 7)`` into the character's world."""
        return _move(poses, self.yaw, self.origin, self.target)

    def to_room(self, poses: np.ndarray) -> np.ndarray:
        """World poses ``(..., 7)`` back into the user's room."""
        return _move(poses, -self.yaw, self.target, self.origin)


def _move(poses: np.ndarray, yaw: float, origin: np.ndarray, target: np.ndarray) -> np.ndarray:
    """Turn poses ``(..., 7)`` by ``yaw`` about +Z around ``origin`` (xy) and put ``origin``
    at ``target``."""
    c, s = np.cos(yaw), np.sin(yaw)
    m = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    q = rot.from_axis_angle(np.array([0.0, 0.0, 1.0]), np.array(yaw))
    pos = poses[..., :3].copy()
    pos[..., :2] -= origin
    pos = pos @ m.T
    pos[..., :2] += target
    quat = rot.mul(np.broadcast_to(q, poses[..., 3:].shape), poses[..., 3:])
    return np.concatenate([pos, rot.normalize(quat)], axis=-1)
