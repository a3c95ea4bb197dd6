"""A pose estimator measured with the policies' metrics: the character placed in the estimate.

A kinematic method outputs a body, not actions. To put it in the same table as the physics
methods, each clip's estimate (every frame, causal: only the devices up to that frame)
becomes a clip on the canonical skeleton (average proportions at the clip's height), is
retargeted onto the run's character exactly as the reference is, and the character *is* that
pose at every frame. The runner's metric probe then compares it with the reference as it
does a simulated body: headset and controller errors, the MPJPE family, MPJRE, jitter (jerk),
foot skating. Penetration comes from a collision pass over the estimated poses (floor and
props at their default placement). An estimator has no contact forces: its own foot-contact
probabilities stand in (a foot "down" above 0.5), so foot skating is how far a foot slides
while the estimator says it is planted, and contact agreement is its contact accuracy.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import torch

from retarget.env.reference import CharacterReference
from retarget.geometry import rotations as rot
from retarget.kinds.pose_estimator import PoseEstimator
from retarget.kinds.state import ReferenceBatch, StepContext
from retarget.motion import skeleton as sk
from retarget.motion.clip import MotionClip

DOWN_NEWTONS = 100.0
"""Force given to a foot the estimator says is down (anything above the probe's 1 N)."""


@dataclass
class Estimate:
    """An estimator's output over a whole motion library, row-aligned with it."""

    clips: list[MotionClip]
    contact_prob: np.ndarray  # (R, 2)
    position_std: np.ndarray  # (R, J) metres


def estimate_library(env, estimator: PoseEstimator, batch: int = 4096) -> Estimate:
    """Run ``estimator`` on every frame of ``env``'s library; clips in the world frame."""
    lib = env.library
    roots, locals_, probs, stds = [], [], [], []
    for begin in range(0, lib.num_frames, batch):
        rows = torch.arange(begin, min(begin + batch, lib.num_frames))
        out, frame = estimator.estimate_rows(rows)
        roots.append(frame.points_out(out.root_pos[:, None])[:, 0].double().numpy())
        quats = rot.from_matrix(out.matrices.double().numpy())
        head = frame.yaw.double().numpy()
        quats[:, 0] = rot.mul(head, quats[:, 0])
        locals_.append(rot.normalize(quats))
        probs.append(torch.sigmoid(out.contact_logits).numpy())
        stds.append(torch.exp(0.5 * out.pos_logvar).numpy())
    root_pos, local_rot = np.concatenate(roots), np.concatenate(locals_)
    contact = np.concatenate(probs)
    clips = []
    for c in range(lib.num_clips):
        a, n = int(lib.start[c]), int(lib.length[c])
        height = float(lib.heights[c])
        clips.append(MotionClip(
            fps=lib.fps, root_pos=root_pos[a : a + n], local_rot=local_rot[a : a + n],
            offsets=sk.rest_offsets(height), contacts=contact[a : a + n] > 0.5,
            name=lib.names[c],
        ))  # fmt: skip
    return Estimate(clips, contact, np.concatenate(stds))


class KinematicRollout:
    """Step contexts of the character placed in an estimate, for the eval runner."""

    def __init__(self, env, estimate: Estimate) -> None:
        self.env = env
        self.estimate = estimate
        self.reference = CharacterReference(env.character, env.world.model, env.layout,
                                            estimate.clips,
                                            hinge=env.options.hinge_elbows)  # fmt: skip
        deepest, mean = env.sim.pose_penetration(self.reference.qpos64)
        self.penetration = (torch.from_numpy(deepest).float(), torch.from_numpy(mean).float())
        groups = env.layout.body_groups
        self.sides = [torch.tensor(groups[s]) for s in ("left_foot", "right_foot")
                      if s in groups]  # fmt: skip
        self.prob = torch.from_numpy(estimate.contact_prob).float()

    def context(self, clip: torch.Tensor, frame: torch.Tensor, step: int) -> StepContext:
        env, lib = self.env, self.env.library
        rows = lib.rows(clip, frame)[:, 0]
        sim = self.reference.pose(rows)
        force = sim.contact_force.clone()
        if len(self.sides) == 2:
            for k, bodies in enumerate(self.sides):
                down = (self.prob[rows, k] > 0.5).float() * DOWN_NEWTONS
                force[:, bodies] = down[:, None]
        sim = replace(sim, contact_force=force, contact_force_up=force)
        labels = env.reference.scene_contacts
        window = lib.rows(clip, frame, env.window_offsets)
        ref = ReferenceBatch(
            pose=env.reference.pose(rows), devices=lib.devices[window],
            window_offsets=tuple(env.window_offsets), contacts=lib.contacts[rows], rows=rows,
            scene_contacts=labels[rows] if labels is not None else None,
            devices_tracked=lib.devices_tracked[window],
        )  # fmt: skip
        n, nu = rows.shape[0], len(env.layout.actuator_names)
        zeros = torch.zeros(n, nu)
        return StepContext(
            layout=env.layout, sim=sim, ref=ref, action=zeros, prev_action=zeros,
            episode_step=torch.full((n,), step, dtype=torch.long),
            dt=env.sim.settings.control_dt, scene=env.scene,
        )  # fmt: skip

    def penetration_at(self, clip: torch.Tensor, frame: torch.Tensor):
        rows = self.env.library.rows(clip, frame)[:, 0]
        return self.penetration[0][rows], self.penetration[1][rows]
