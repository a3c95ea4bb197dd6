"""Batched rotation helpers in torch and the character's heading frame.

Quaternions are ``wxyz`` unit quaternions, Z is up, and every function works on whole batches
(any leading shape, broadcasting) so sensors and rewards never loop over environments. Rotations
act on column vectors and compose like matrices: ``quat_mul(a, b)`` applies ``b`` first. The
conventions match :mod:`retarget.motion.rotations` (the numpy twin used on motion data).

The *heading frame* of a character is the world frame turned about Z by the character's yaw
and moved horizontally to the character's root. Observations expressed in it do not change when
the whole world (character, reference and devices) is rotated about the vertical axis or
translated horizontally, so a policy does not have to learn the same behaviour once per facing
direction. Heights are kept as world heights (height above the floor at z = 0) because how high
the headset is carries meaning (standing, crouching, sitting); pass ``keep_height=False`` to
subtract the root height as well.
"""

from __future__ import annotations

import torch

__all__ = [
    "heading_quat",
    "quat_angle",
    "quat_apply",
    "quat_conj",
    "quat_mul",
    "quat_normalize",
    "quat_to_6d",
    "quat_to_matrix",
    "rotation_distance",
    "to_heading_points",
    "to_heading_quats",
    "to_heading_vectors",
    "yaw_quat",
]


def quat_normalize(q: torch.Tensor, eps: float = 1e-9) -> torch.Tensor:
    """Unit quaternions (a zero quaternion stays finite rather than becoming NaN)."""
    return q / q.norm(dim=-1, keepdim=True).clamp_min(eps)


def quat_conj(q: torch.Tensor) -> torch.Tensor:
    """Conjugate, the inverse of a unit quaternion."""
    return torch.cat([q[..., :1], -q[..., 1:]], dim=-1)


def quat_mul(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """Hamilton product ``a * b`` (rotation ``b`` first, then ``a``), broadcasting."""
    aw, ax, ay, az = a[..., 0], a[..., 1], a[..., 2], a[..., 3]
    bw, bx, by, bz = b[..., 0], b[..., 1], b[..., 2], b[..., 3]
    return torch.stack(
        [
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ],
        dim=-1,
    )


def quat_apply(q: torch.Tensor, v: torch.Tensor) -> torch.Tensor:
    """Rotate vectors ``v`` (..., 3) by unit quaternions ``q`` (..., 4), broadcasting.

    Uses ``v' = v + 2 w (u x v) + 2 u x (u x v)`` with ``u`` the vector part: no matrices are
    built, which keeps it cheap for the (N, B, 3) arrays of every step.
    """
    w = q[..., :1]
    u = q[..., 1:]
    t = 2.0 * torch.linalg.cross(u, v, dim=-1)
    return v + w * t + torch.linalg.cross(u, t, dim=-1)


def quat_to_matrix(q: torch.Tensor) -> torch.Tensor:
    """Rotation matrices ``(..., 3, 3)`` of unit quaternions ``(..., 4)``."""
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    rows = [
        1 - 2 * (y * y + z * z),
        2 * (x * y - w * z),
        2 * (x * z + w * y),
        2 * (x * y + w * z),
        1 - 2 * (x * x + z * z),
        2 * (y * z - w * x),
        2 * (x * z - w * y),
        2 * (y * z + w * x),
        1 - 2 * (x * x + y * y),
    ]
    return torch.stack(rows, dim=-1).reshape(*q.shape[:-1], 3, 3)


def quat_to_6d(q: torch.Tensor) -> torch.Tensor:
    """The continuous 6D representation (Zhou et al. 2019): the first two matrix columns.

    Laid out as ``[c0x, c0y, c0z, c1x, c1y, c1z]`` (the rotated x axis, then the rotated y
    axis). Unlike quaternions it has no sign ambiguity and no discontinuity, which is why
    networks get it instead of ``wxyz``.
    """
    m = quat_to_matrix(q)
    return torch.cat([m[..., :, 0], m[..., :, 1]], dim=-1)


def quat_angle(q: torch.Tensor) -> torch.Tensor:
    """Rotation angle in ``[0, pi]`` of unit quaternions: the norm of their axis-angle vector.

    ``2 atan2(|v|, |w|)`` is exact near 0 and pi (unlike ``2 acos(w)``) and treats ``q`` and
    ``-q`` alike.
    """
    return 2.0 * torch.atan2(q[..., 1:].norm(dim=-1), q[..., 0].abs())


def rotation_distance(q_ref: torch.Tensor, q_sim: torch.Tensor) -> torch.Tensor:
    """The paper's orientation distance: the axis-angle norm of ``q_ref * q_sim^-1``."""
    return quat_angle(quat_mul(q_ref, quat_conj(q_sim)))


def yaw_quat(yaw: torch.Tensor) -> torch.Tensor:
    """Quaternions of rotations by ``yaw`` radians about +Z."""
    half = 0.5 * yaw
    zero = torch.zeros_like(half)
    return torch.stack([torch.cos(half), zero, zero, torch.sin(half)], dim=-1)


def heading_quat(q: torch.Tensor) -> torch.Tensor:
    """The yaw-only part of orientations ``q``: the direction the body's x axis points in.

    The heading is the azimuth of the rotated local x axis projected on the ground plane. When
    that axis is vertical (a body lying pointed straight up) the azimuth is undefined;
    ``atan2(0, 0) = 0`` keeps it finite.
    """
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    fx = 1.0 - 2.0 * (y * y + z * z)  # first column of the rotation matrix
    fy = 2.0 * (x * y + w * z)
    return yaw_quat(torch.atan2(fy, fx))


def _per_env(t: torch.Tensor, ndim: int) -> torch.Tensor:
    """Insert singleton dims after the env dim so ``(N, k)`` broadcasts against ``ndim`` dims."""
    return t.reshape(t.shape[0], *([1] * (ndim - 2)), t.shape[-1])


def to_heading_points(
    points: torch.Tensor,
    root_pos: torch.Tensor,
    root_quat: torch.Tensor,
    *,
    keep_height: bool = True,
) -> torch.Tensor:
    """World points ``(N, ..., 3)`` in the heading frame of roots ``(N, 3)``/``(N, 4)``.

    The origin is the root's ground projection (``keep_height=True``: z stays the world height)
    or the root itself (``keep_height=False``).
    """
    origin = root_pos
    if keep_height:
        origin = torch.cat([root_pos[:, :2], torch.zeros_like(root_pos[:, 2:])], dim=-1)
    inv = quat_conj(heading_quat(root_quat))
    rel = points - _per_env(origin, points.ndim)
    return quat_apply(_per_env(inv, points.ndim), rel)


def to_heading_vectors(vectors: torch.Tensor, root_quat: torch.Tensor) -> torch.Tensor:
    """Free vectors (velocities) ``(N, ..., 3)`` in the heading frame: rotated, not moved."""
    inv = quat_conj(heading_quat(root_quat))
    return quat_apply(_per_env(inv, vectors.ndim), vectors)


def to_heading_quats(quats: torch.Tensor, root_quat: torch.Tensor) -> torch.Tensor:
    """World orientations ``(N, ..., 4)`` relative to the heading of roots ``(N, 4)``."""
    inv = quat_conj(heading_quat(root_quat))
    return quat_mul(_per_env(inv, quats.ndim), quats)
