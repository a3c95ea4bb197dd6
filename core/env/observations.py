"""Observation sources of the environment itself: proprioception and privileged reference.

Both are expressed in the simulated character's heading frame (yaw removed, origin at the
root's ground point), so the policy is invariant to where and which way the user walks.
``privileged`` is what only the critic sees (asymmetric actor-critic): the reference pose now
and a few frames ahead, which a headset user can never provide.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch

from retarget.geometry.heading import heading_cos_sin, quat_to_6d, unyaw
from retarget.kinds.state import Layout, StepContext
from retarget.kinds.step import StepNeeds


def proprio_size(layout: Layout) -> int:
    b = layout.num_bodies
    return 1 + 6 + 6 + (layout.nq - 7) + (layout.nv - 6) + b * (3 + 6 + 3 + 3)


def proprio(ctx: StepContext) -> torch.Tensor:
    """Root height, root tilt (6D), root velocities, joint angles/velocities, and every body's
    position, orientation (6D) and velocities relative to the root, in the heading frame.

    The heading's cosine/sine are computed once and applied with :func:`unyaw` to positions,
    velocities and the two columns of each 6D rotation alike (rotating a rotation's columns is
    rotating the rotation): this runs every control step for every env.
    """
    s = ctx.sim
    root_pos, root_quat = s.qpos[:, :3], s.qpos[:, 3:7]
    n, b = ctx.num_envs, s.body_pos.shape[1]
    c, sn = heading_cos_sin(root_quat)
    cols = quat_to_6d(torch.cat([root_quat[:, None], s.body_quat], dim=1)).reshape(n, -1, 3)
    # free joint: linear velocity in the world frame, angular velocity in the body frame;
    # one rotation for the 6D columns and every vector (the per-call cost dominates at batch 1)
    turned = unyaw(torch.cat(
        [cols, s.qvel[:, None, :3], s.body_pos - root_pos[:, None], s.body_linvel,
         s.body_angvel], 1
    ), c, sn)  # fmt: skip
    split = 2 * (b + 1)
    rot6, vectors = turned[:, :split].reshape(n, b + 1, 6), turned[:, split:]
    return torch.cat(
        [
            root_pos[:, 2:3],
            rot6[:, 0],
            vectors[:, 0],
            s.qvel[:, 3:6],
            s.qpos[:, 7:],
            s.qvel[:, 6:],
            vectors[:, 1 : 1 + b].reshape(n, -1),
            rot6[:, 1:].reshape(n, -1),
            vectors[:, 1 + b :].reshape(n, -1),
        ],
        dim=-1,
    ).float()


def privileged_size(layout: Layout, frames: int) -> int:
    return 3 + (layout.nq - 7) + frames * layout.num_bodies * 3


def privileged(ctx: StepContext, offsets: tuple[int, ...]) -> torch.Tensor:
    """Reference root offset and joint angles now, and reference body positions at the future
    frames ``offsets``, all relative to the simulated root in its heading frame."""
    s, ref = ctx.sim, ctx.ref.pose
    root_pos, root_quat = s.qpos[:, :3], s.qpos[:, 3:7]
    n = ctx.num_envs
    c, sn = heading_cos_sin(root_quat)
    root_offset = unyaw((ref.qpos[:, :3] - root_pos)[:, None], c, sn)[:, 0]
    ahead = torch.stack([ctx.ref.future[k].body_pos for k in offsets], dim=1)  # (N, F, B, 3)
    future = unyaw(ahead - root_pos[:, None, None], c, sn)
    return torch.cat(
        [root_offset, ref.qpos[:, 7:] - s.qpos[:, 7:], future.reshape(n, -1)], dim=-1
    ).float()


@dataclass
class Proprio:
    """Observation source ``proprio`` (:func:`proprio`)."""

    layout: Layout
    name: str = "proprio"

    @property
    def size(self) -> int:
        return proprio_size(self.layout)

    @property
    def shape(self) -> tuple[int, ...]:
        return (self.size,)

    def needs(self) -> StepNeeds:
        return StepNeeds()

    def reset(self, env_ids: torch.Tensor) -> None:
        """Stateless: computed from each step's state alone."""

    def compute(self, ctx: StepContext) -> torch.Tensor:
        return proprio(ctx)


@dataclass
class Privileged:
    """Observation source ``privileged`` (:func:`privileged`): the critic's view of the
    reference, asking the step for the reference at ``offsets`` frames ahead."""

    layout: Layout
    offsets: tuple[int, ...]
    name: str = "privileged"

    @property
    def size(self) -> int:
        return privileged_size(self.layout, len(self.offsets))

    @property
    def shape(self) -> tuple[int, ...]:
        return (self.size,)

    def needs(self) -> StepNeeds:
        return StepNeeds(reference_offsets=self.offsets)

    def reset(self, env_ids: torch.Tensor) -> None:
        """Stateless: computed from each step's state alone."""

    def compute(self, ctx: StepContext) -> torch.Tensor:
        return privileged(ctx, self.offsets)
