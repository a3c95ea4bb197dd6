"""Reaching the controllers: two-bone IK that puts an estimated body's wrists where the
controllers say they are, along the person's own arm.

A pose estimator predicts joint rotations; its hands come from forward kinematics down a chain
of six joints (root, three spine joints, collar, shoulder, elbow), so small rotation errors add
up to centimetres at the hands on motion it never saw (4 cm at the wrists on held-out corpus
gestures), although the controllers give each wrist's position and orientation outright (the
controller sits at a fixed mount on the wrist, :mod:`retarget.motion.devices`). This closes
that gap without training: per arm, the shoulder and elbow rotations are changed by the
smallest rotations that bring the wrist onto the controller's wrist point, keeping the arm's
swivel plane (where the elbow points) as the network predicted it, and the wrist takes the
controller's orientation. Batched in torch, tens of microseconds per frame.

The arm must be the person's. The rotations are what the character copies, and the same wrist
point reached with other bone lengths is other rotations: reached on the average skeleton,
the Bandai Namco performers' arms (shoulders 8 cm narrower, the rest shorter) put the
character's hands farther from the reference's than no reach at all (9.4 against 5.9 cm on
held-out gestures). So the chain is the skeleton the motions give (a BVH's own bones),
:attr:`MotionLibrary.bones`; an application running the exported network reaches along its
user's measured arm the same way.
"""

from __future__ import annotations

import torch

from retarget.learn.pose_samples import (
    PARENTS,
    J,
    matrix_to_6d,
    sixd_to_matrix,
    skeleton_globals,
)
from retarget.motion import skeleton as sk
from retarget.motion.devices import MOUNT_OFFSETS_175

ARMS = tuple(
    tuple(sk.joint_index(f"{side}_{j}") for j in ("shoulder", "elbow", "wrist"))
    for side in ("left", "right")
)
"""(shoulder, elbow, wrist) joint indices of the left and right arm."""


def _align(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """Rotation matrices ``(B, 3, 3)`` turning unit vectors ``a`` onto ``b`` the shortest way."""
    v = torch.cross(a, b, dim=-1)
    c = (a * b).sum(-1).clamp(min=-1.0 + 1e-6)
    k = torch.zeros(a.shape[0], 3, 3, dtype=a.dtype)
    k[:, 0, 1], k[:, 0, 2], k[:, 1, 2] = -v[:, 2], v[:, 1], -v[:, 0]
    k = k - k.transpose(1, 2)
    eye = torch.eye(3, dtype=a.dtype).expand_as(k)
    return eye + k + (k @ k) / (1.0 + c)[:, None, None]


def wrist_targets(
    controllers: torch.Tensor, heights: torch.Tensor
) -> tuple[torch.Tensor, torch.Tensor]:
    """Wrist positions ``(B, 2, 3)`` and rotation matrices ``(B, 2, 3, 3)`` from controller
    poses ``(B, 2, 7)`` (position, wxyz; the estimator's frame) of people ``heights`` tall."""
    from retarget.geometry.heading import quat_to_matrix

    rot = quat_to_matrix(controllers[..., 3:7])
    mount = torch.as_tensor(MOUNT_OFFSETS_175[1:], dtype=controllers.dtype)  # (2, 3)
    mount = mount[None] * (heights / sk.REFERENCE_HEIGHT)[:, None, None]
    pos = controllers[..., :3] - (rot @ mount[..., None])[..., 0]
    return pos, rot


def reach(
    root_pos: torch.Tensor, local: torch.Tensor, bones: torch.Tensor,
    wrist_pos: torch.Tensor, wrist_rot: torch.Tensor | None = None,
) -> torch.Tensor:  # fmt: skip
    """Local rotation matrices ``(B, J, 3, 3)`` of the pose ``root_pos``/``local`` on the
    skeleton ``bones`` (bone offsets ``(B, J, 3)``) with both wrists at ``wrist_pos``
    ``(B, 2, 3)`` (as near as the arm's length allows) and, when given, their global rotations
    ``wrist_rot``."""
    local = local.clone()
    offsets = bones.to(root_pos)
    pos, glob = skeleton_globals(root_pos, local, offsets)
    for arm, (s, e, w) in enumerate(ARMS):
        target = wrist_pos[:, arm]
        l1 = offsets[:, e].norm(dim=-1)
        l2 = offsets[:, w].norm(dim=-1)
        to_target = target - pos[:, s]
        d = to_target.norm(dim=-1).clamp(min=(l1 - l2).abs() + 1e-4, max=l1 + l2 - 1e-4)
        u = torch.nn.functional.normalize(to_target, dim=-1, eps=1e-8)
        upper = pos[:, e] - pos[:, s]
        pole = upper - (upper * u).sum(-1, keepdim=True) * u  # where the elbow points now
        fallback = torch.tensor([0.0, 0.0, -1.0], dtype=pole.dtype).expand_as(pole)
        small = pole.norm(dim=-1, keepdim=True) < 1e-6
        pole = torch.nn.functional.normalize(torch.where(small, fallback, pole), dim=-1)
        a = (l1 * l1 - l2 * l2 + d * d) / (2 * d)
        h = (l1 * l1 - a * a).clamp(min=0).sqrt()
        elbow = pos[:, s] + a[:, None] * u + h[:, None] * pole
        turn_s = _align(torch.nn.functional.normalize(upper, dim=-1),
                        torch.nn.functional.normalize(elbow - pos[:, s], dim=-1))  # fmt: skip
        g_s = turn_s @ glob[s]
        g_e0 = g_s @ local[:, e]
        fore = torch.nn.functional.normalize((g_e0 @ offsets[:, w, :, None])[..., 0], dim=-1)
        reach_dir = pos[:, s] + u * d[:, None] - elbow
        g_e = _align(fore, torch.nn.functional.normalize(reach_dir, dim=-1)) @ g_e0
        local[:, s] = glob[PARENTS[s]].transpose(1, 2) @ g_s
        local[:, e] = g_s.transpose(1, 2) @ g_e
        if wrist_rot is not None:
            local[:, w] = g_e.transpose(1, 2) @ wrist_rot[:, arm]
    return local


class ReachStage(torch.nn.Module):
    """The reach as a step after a deployed estimator (what ``retarget export`` writes as
    ``reach.onnx``): its output ``(B, 3 + 6J + ...)`` (root position, 6D rotations, then
    whatever follows, kept), the controllers ``(B, 2, 7)`` in the same headset frame, the
    user's bone offsets ``(B, J, 3)`` and height ``(B,)`` -> the same output with the arms'
    rotations reached."""

    def forward(
        self, estimate: torch.Tensor, controllers: torch.Tensor, bones: torch.Tensor,
        height: torch.Tensor,
    ) -> torch.Tensor:  # fmt: skip
        a = 3 + J * 6
        root = estimate[:, :3]
        local = sixd_to_matrix(estimate[:, 3:a].reshape(-1, J, 6))
        wrist_pos, wrist_rot = wrist_targets(controllers, height)
        reached = matrix_to_6d(reach(root, local, bones, wrist_pos, wrist_rot))
        return torch.cat([root, reached.reshape(-1, J * 6), estimate[:, a:]], dim=-1)
