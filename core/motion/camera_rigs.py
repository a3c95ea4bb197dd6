"""Headset camera rigs: where a headset's tracking cameras sit and what they see.

A camera is a pose in the headset frame (+X where the face looks, +Y left, +Z up: the device
convention of :mod:`retarget.motion.devices`), given as a position and a yaw (left +) and pitch
(up +) of its optical axis from straight ahead, plus a vertical field of view. The cameras are
rendered as pinholes; the real lenses are fisheyes with wider views, so the fields of view
below are what a pinhole of the same sensor keeps without extreme stretching.

* ``quest2``: Meta Quest 2 has four monochrome tracking cameras at the front corners of the
  visor, two looking down-and-out, two up-and-out, so that controllers held low or raised are
  seen. Positions are the visor corners of a ~19 cm wide headset (+-7 cm sideways, +-3 cm up,
  4 cm ahead of the eyes); axes 40 deg outward, 50 deg down / 20 deg up, 100 deg field of view
  (estimates from teardown photos and the SimXR paper's description: the exact calibration is
  not published, and a user's rig in a recipe overrides these).
* ``aria``: Project Aria glasses have two SLAM cameras at the outer front corners of the frame
  looking forward-and-out (+-7 cm, 1 cm up; 30 deg outward, 10 deg down, 110 deg).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from pydantic import BaseModel, ConfigDict, Field

if TYPE_CHECKING:
    import numpy as np


class Camera(BaseModel):
    """One camera on a headset (see the module docstring for the frame)."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    name: str = Field(pattern=r"^[a-z][a-z0-9_]{0,31}$")
    pos: tuple[float, float, float] = Field(description="metres in the headset frame")
    yaw: float = Field(0.0, ge=-180, le=180, description="degrees, left +")
    pitch: float = Field(0.0, ge=-90, le=90, description="degrees, up +")
    fovy: float = Field(100.0, gt=10, lt=170, description="vertical field of view, degrees")

    def quat(self) -> np.ndarray:
        """wxyz rotation from a MuJoCo camera frame (looks along -Z, +Y up) to the headset."""
        import numpy as np

        from retarget.geometry import rotations as rot

        ahead = np.array([[0.0, 0.0, -1.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])  # cam -> head
        y, p = np.radians(self.yaw), np.radians(self.pitch)
        turn = np.array([[np.cos(y), -np.sin(y), 0.0], [np.sin(y), np.cos(y), 0.0], [0, 0, 1.0]])
        tilt = np.array([[np.cos(p), 0.0, -np.sin(p)], [0, 1.0, 0], [np.sin(p), 0.0, np.cos(p)]])
        return rot.from_matrix(turn @ tilt @ ahead)


class CameraRig(BaseModel):
    """A headset's cameras, rendered side by side into one observation ``(C, H, W)``."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    cameras: tuple[Camera, ...] = Field(min_length=1, max_length=8)


RIGS: dict[str, CameraRig] = {
    "quest2": CameraRig(
        cameras=(
            Camera(name="low_left", pos=(0.04, 0.07, -0.03), yaw=40, pitch=-50),
            Camera(name="low_right", pos=(0.04, -0.07, -0.03), yaw=-40, pitch=-50),
            Camera(name="up_left", pos=(0.04, 0.07, 0.03), yaw=40, pitch=20),
            Camera(name="up_right", pos=(0.04, -0.07, 0.03), yaw=-40, pitch=20),
        )
    ),
    "aria": CameraRig(
        cameras=(
            Camera(name="left", pos=(0.02, 0.07, 0.01), yaw=30, pitch=-10, fovy=110),
            Camera(name="right", pos=(0.02, -0.07, 0.01), yaw=-30, pitch=-10, fovy=110),
        )
    ),
}
"""The packaged rigs by name."""
