"""Idle starts: some training episodes begin with the body standing idle, not in the
reference's pose, at the start of a clip that sets off from standing.

Reference state initialisation starts every episode in the pose of its reference frame, so a
policy never has to get from a pose of its own into the motion. A live session cannot do that:
``retarget serve`` and ``play --input`` start the avatar standing in the character's idle pose
(the same frame of the same generated idle clip) whatever the user's first pose, and the
user then sets off. Measured on held-out walks set off from standing
(``benchmarks/follow_recordings.py``), the three-point student given the reference's own
devices tracks 2 of 5 starting in the reference pose and none of 5 from the idle pose. With
``env.idle_starts: p``, a share ``p`` of the random episode starts (training; evaluation
places its own) goes to frame 0 of a clip made by ``motions.rest_ends`` to set off from
standing, with the body in the idle pose, turned to the reference's heading and standing
where the reference's root is, at rest.
"""

from __future__ import annotations

import numpy as np
import torch

from retarget.geometry import rotations as rot


class IdleStarts:
    """Which random starts begin idle, and the idle pose placed under a reference root."""

    def __init__(self, share: float, from_rest: torch.Tensor, idle_qpos: np.ndarray) -> None:
        self.share = float(share)
        self.from_rest = from_rest.long()
        self.idle_qpos = np.asarray(idle_qpos, dtype=np.float64)

    def choose(
        self, clip: torch.Tensor, frame: torch.Tensor, generator: torch.Generator
    ) -> torch.Tensor:
        """Redirect a share of the sampled starts (in place) to frame 0 of a random clip that
        sets off from rest; returns the mask of those starts (all false without such clips)."""
        n = int(clip.numel())
        idle = torch.rand(n, generator=generator, dtype=torch.float64) < self.share
        if self.from_rest.numel() == 0 or not bool(idle.any()):
            return torch.zeros(n, dtype=torch.bool)
        k = int(idle.sum())
        pick = torch.randint(int(self.from_rest.numel()), (k,), generator=generator)
        clip[idle] = self.from_rest[pick].to(clip.dtype)
        frame[idle] = 0
        return idle

    def pose(self, ref_qpos: np.ndarray) -> np.ndarray:
        """The idle pose standing under each reference pose (see :func:`stand_under`)."""
        return stand_under(self.idle_qpos, ref_qpos)


def stand_under(idle_qpos: np.ndarray, ref_qpos: np.ndarray) -> np.ndarray:
    """The idle pose ``(k, nq)`` standing where each reference pose ``(k, nq)`` has its root
    (horizontal position and heading; the idle pose's own height and joints)."""
    idle_qpos = np.asarray(idle_qpos, dtype=np.float64)
    out = np.repeat(idle_qpos[None], len(ref_qpos), axis=0)
    turn = rot.yaw(ref_qpos[:, 3:7]) - float(rot.yaw(idle_qpos[3:7]))
    q = rot.from_axis_angle(np.array([0.0, 0.0, 1.0]), turn)
    out[:, 3:7] = rot.normalize(rot.mul(q, out[:, 3:7]))
    out[:, :2] = ref_qpos[:, :2]
    return out
