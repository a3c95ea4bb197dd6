"""Observation sources of the environment itself: proprioception and privileged reference.

Both are expressed in the simulated character's heading frame (yaw removed, origin at the
root's ground point), so the policy is invariant to where and which way the user walks.
``privileged`` is what only the critic sees (asymmetric actor-critic): the reference pose now
and a few frames ahead, which a headset user can never provide.
"""

from __future__ import annotations

import torch

from retarget.heading import quat_to_6d, to_heading_points, to_heading_quats, to_heading_vectors
from retarget.state import Layout, StepContext

FUTURE_POS = "future_body_pos"
"""``ctx.ref.extras`` key: reference body positions at the privileged offsets ``(N, F, B, 3)``."""


def proprio_size(layout: Layout) -> int:
    b = layout.num_bodies
    return 1 + 6 + 6 + (layout.nq - 7) + (layout.nv - 6) + b * (3 + 6 + 3 + 3)


def proprio(ctx: StepContext) -> torch.Tensor:
    """Root height, root tilt (6D), root velocities, joint angles/velocities, and every body's
    position, orientation (6D) and velocities relative to the root, in the heading frame."""
    s = ctx.sim
    root_pos, root_quat = s.qpos[:, :3], s.qpos[:, 3:7]
    n = ctx.num_envs
    tilt = quat_to_6d(to_heading_quats(root_quat[:, None], root_quat))[:, 0]
    # free joint: linear velocity in the world frame, angular velocity in the body frame
    root_vel = torch.cat(
        [to_heading_vectors(s.qvel[:, None, :3], root_quat), s.qvel[:, None, 3:6]], 1
    )
    body_pos = to_heading_points(s.body_pos, root_pos, root_quat, keep_height=False)
    body_rot = quat_to_6d(to_heading_quats(s.body_quat, root_quat))
    body_vel = to_heading_vectors(torch.cat([s.body_linvel, s.body_angvel], dim=1), root_quat)
    return torch.cat(
        [
            root_pos[:, 2:3],
            tilt,
            root_vel.reshape(n, -1),
            s.qpos[:, 7:],
            s.qvel[:, 6:],
            body_pos.reshape(n, -1),
            body_rot.reshape(n, -1),
            body_vel.reshape(n, -1),
        ],
        dim=-1,
    ).float()


def privileged_size(layout: Layout, frames: int) -> int:
    return 3 + (layout.nq - 7) + frames * layout.num_bodies * 3


def privileged(ctx: StepContext) -> torch.Tensor:
    """Reference root offset and joint angles now, and reference body positions at future
    frames, all relative to the simulated root in its heading frame."""
    s, ref = ctx.sim, ctx.ref.pose
    root_pos, root_quat = s.qpos[:, :3], s.qpos[:, 3:7]
    n = ctx.num_envs
    root_offset = to_heading_vectors((ref.qpos[:, :3] - root_pos)[:, None], root_quat)[:, 0]
    future = to_heading_points(ctx.ref.extras[FUTURE_POS], root_pos, root_quat, keep_height=False)
    return torch.cat(
        [root_offset, ref.qpos[:, 7:] - s.qpos[:, 7:], future.reshape(n, -1)], dim=-1
    ).float()
