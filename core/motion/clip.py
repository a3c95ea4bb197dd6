"""A motion clip on the canonical skeleton, and its forward kinematics.

Every reader produces a :class:`MotionClip`; everything downstream (resampling, contacts, device
synthesis, the motion library, retargeting to characters) consumes only this, so a new source
format only has to get this one structure right.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from retarget.geometry import rotations as rot
from retarget.motion import skeleton as sk


def forward_kinematics(
    root_pos: np.ndarray, local_rot: np.ndarray, offsets: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Global joint positions ``(T, J, 3)`` and rotations ``(T, J, 4)`` of the canonical skeleton.

    Vectorised over frames; the loop runs over the 22 joints only.
    """
    t = root_pos.shape[0]
    pos = np.empty((t, sk.NUM_JOINTS, 3))
    grot = np.empty((t, sk.NUM_JOINTS, 4))
    pos[:, 0] = root_pos
    grot[:, 0] = local_rot[:, 0]
    for j in range(1, sk.NUM_JOINTS):
        p = sk.PARENTS[j]
        pos[:, j] = pos[:, p] + rot.apply(grot[:, p], offsets[j])
        grot[:, j] = rot.mul(grot[:, p], local_rot[:, j])
    return pos, grot


def local_from_global(global_rot: np.ndarray) -> np.ndarray:
    """Local rotations ``(T, J, 4)`` from global ones (inverse of the rotation part of FK)."""
    local = np.array(global_rot, dtype=np.float64, copy=True)
    parents = np.array(sk.PARENTS[1:])
    local[:, 1:] = rot.mul(rot.conj(global_rot[:, parents]), global_rot[:, 1:])
    return rot.normalize(local)


@dataclass
class MotionClip:
    """One clip of human motion on the canonical skeleton (see :mod:`retarget.motion.skeleton`).

    ``local_rot`` is relative to the canonical T-pose (identity = T-pose), whatever the rest
    pose of the file it came from. ``offsets`` are this subject's bone vectors in the T-pose, so
    forward kinematics reproduces the recorded joint positions. ``contacts`` flags per frame
    whether the left/right foot is planted.
    """

    fps: float
    root_pos: np.ndarray  # (T, 3) metres, world Z up
    local_rot: np.ndarray  # (T, J, 4) wxyz
    offsets: np.ndarray  # (J, 3) metres
    contacts: np.ndarray | None = None  # (T, 2) bool, left/right foot
    name: str = ""
    source: Path | None = None
    skeleton: str = "canonical"  # which source skeleton this was mapped from
    meta: dict[str, object] = field(default_factory=dict)
    _fk: tuple[np.ndarray, np.ndarray] | None = field(default=None, repr=False, compare=False)

    def __post_init__(self) -> None:
        self.root_pos = np.asarray(self.root_pos, dtype=np.float64)
        self.local_rot = np.asarray(self.local_rot, dtype=np.float64)
        self.offsets = np.asarray(self.offsets, dtype=np.float64)
        t = self.root_pos.shape[0]
        if self.root_pos.shape != (t, 3):
            raise ValueError(f"root_pos must be (T, 3), got {self.root_pos.shape}")
        if self.local_rot.shape != (t, sk.NUM_JOINTS, 4):
            raise ValueError(
                f"local_rot must be ({t}, {sk.NUM_JOINTS}, 4), got {self.local_rot.shape}"
            )
        if self.offsets.shape != (sk.NUM_JOINTS, 3):
            raise ValueError(f"offsets must be ({sk.NUM_JOINTS}, 3), got {self.offsets.shape}")
        if self.contacts is None:
            self.contacts = np.zeros((t, 2), dtype=bool)
        self.contacts = np.asarray(self.contacts, dtype=bool)
        if self.contacts.shape != (t, 2):
            raise ValueError(f"contacts must be ({t}, 2), got {self.contacts.shape}")

    @property
    def num_frames(self) -> int:
        return int(self.root_pos.shape[0])

    @property
    def duration(self) -> float:
        """Seconds from the first to the last frame."""
        return max(self.num_frames - 1, 0) / self.fps

    @property
    def dt(self) -> float:
        return 1.0 / self.fps

    def _forward(self) -> tuple[np.ndarray, np.ndarray]:
        if self._fk is None:
            self._fk = forward_kinematics(self.root_pos, self.local_rot, self.offsets)
        return self._fk

    @property
    def global_pos(self) -> np.ndarray:
        """Joint positions ``(T, J, 3)`` (computed once, cached)."""
        return self._forward()[0]

    @property
    def global_rot(self) -> np.ndarray:
        """Joint orientations ``(T, J, 4)`` in the world frame (computed once, cached)."""
        return self._forward()[1]

    @property
    def height(self) -> float:
        """The subject's standing height implied by its bone lengths, metres.

        Uses bone lengths only (not the clip's foot heights), so every clip of one subject
        reports the same height.
        """
        return sk.estimate_height(self.offsets)

    def with_(self, **changes: object) -> MotionClip:
        """A copy with some fields replaced (the FK cache is dropped)."""
        changes.setdefault("_fk", None)
        return replace(self, **changes)  # type: ignore[arg-type]

    def slice(self, start: int, stop: int) -> MotionClip:
        """Frames ``[start, stop)`` as a new clip."""
        return self.with_(
            root_pos=self.root_pos[start:stop],
            local_rot=self.local_rot[start:stop],
            contacts=self.contacts[start:stop] if self.contacts is not None else None,
        )
