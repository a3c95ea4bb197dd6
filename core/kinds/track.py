"""What a planner found for one clip: the path, its actions and PHC's figures of it.

Every planner (:class:`retarget.Planner`) returns one; :mod:`retarget.expert.store`
writes it, and students learn from the states and actions in it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # numpy is imported where a track is used: the CLI starts without it
    import numpy as np


@dataclass
class Track:
    """What the planner found for one clip; frame 0 is the placed reference pose."""

    clip: str
    fps: float
    actions: np.ndarray  # (T-1, nu): action taken at frame t, reaching frame t+1
    qpos: np.ndarray  # (T, nq) the whole model's (scene joints included)
    qvel: np.ndarray  # (T, nv)
    body_pos: np.ndarray  # (T, B, 3) the character's bodies
    ref_body_pos: np.ndarray  # (T, B, 3) the reference's
    ref_qpos0: np.ndarray  # the reference pose at frame 0 (checks a replay's library)
    cpu_seconds: float
    demos: dict[str, np.ndarray] = field(default_factory=dict)
    """Beam members other than the best path, one row per (segment, member): their start
    state (``state_*`` fields of ``BatchedSim.STATE_FIELDS``), ``frame``, ``prev_action``,
    ``actions`` (rows, segment, nu) and ``steps`` (how many of them are real)."""
    rescued: int = 0
    """Segments of the kept pass planned again by the rescue (``ExpertConfig.rescue``)."""

    @property
    def frames(self) -> int:
        return len(self.qpos)

    @property
    def motion_seconds(self) -> float:
        return (self.frames - 1) / self.fps

    def metrics(self, threshold: float = 0.5) -> dict[str, float | bool | None]:
        """PHC's figures of the best path: success (no frame with a mean body error above
        ``threshold`` m), root-relative MPJPE and G-MPJPE (mm), CPU-s per motion-second."""
        import numpy as np

        err = np.linalg.norm(self.body_pos - self.ref_body_pos, axis=-1)  # (T, B)
        rel = np.linalg.norm(
            (self.body_pos - self.body_pos[:, :1]) - (self.ref_body_pos - self.ref_body_pos[:, :1]),
            axis=-1,
        )
        per_frame = err.mean(-1)
        over = np.flatnonzero(per_frame > threshold)
        return {
            "success_clip": bool(over.size == 0),
            "failed_at_s": float(over[0] / self.fps) if over.size else None,
            "mpjpe_mm": float(rel[1:].mean() * 1000),
            "g_mpjpe_mm": float(err[1:].mean() * 1000),
            "max_body_error_m": float(per_frame.max()),
            "motion_seconds": self.motion_seconds,
            "cpu_seconds": self.cpu_seconds,
            "cpu_s_per_motion_s": self.cpu_seconds / max(self.motion_seconds, 1e-9),
            "rescued_segments": self.rescued,
        }
