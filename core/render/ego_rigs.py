"""The headset camera rigs, read where the ego renderer is: they live in
:mod:`retarget.motion.camera_rigs` (a device recording names its rig, so the motion layer
owns them) and are re-exported here for code written against this module."""

from retarget.motion.camera_rigs import RIGS, Camera, CameraRig

__all__ = ["RIGS", "Camera", "CameraRig"]
