"""Batched rotation helpers in torch and the character's heading frame.

Quaternions are ``wxyz`` unit quaternions, Z is up, and every function works on whole batches
(any leading shape, broadcasting) so sensors and rewards never loop over environments. Rotations
act on column vectors and compose like matrices: ``quat_mul(a, b)`` applies ``b`` first. The
conventions match :mod:`retarget.geometry.rotations` (the numpy twin used on motion data).

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
    "ground_origin",
    "heading_cos_sin",
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
    "unyaw",
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
    networks get it instead of ``wxyz``. Each entry is a quadratic form of the (unit)
    quaternion, so all six come from one outer product and one matrix product: at the sizes
    of an observation (a few bodies per environment) the fixed cost per torch call dominates,
    and this is three calls where the element-wise formulas take two dozen.
    """
    outer = (q.unsqueeze(-1) * q.unsqueeze(-2)).flatten(-2)
    m, b = _constants("sixd", q.dtype)
    return outer @ m + b


# vec(q q^T) (index 4 i + j holds q_i q_j, q = wxyz) -> the six entries of quat_to_6d
_SIXD_M = torch.zeros(16, 6)
_SIXD_M[[10, 15], 0] = -2.0  # 1 - 2 (y^2 + z^2)
_SIXD_M[[6, 9, 3, 12], 1] = 1.0  # 2 (x y + w z)
_SIXD_M[[7, 13], 2], _SIXD_M[[2, 8], 2] = 1.0, -1.0  # 2 (x z - w y)
_SIXD_M[[6, 9], 3], _SIXD_M[[3, 12], 3] = 1.0, -1.0  # 2 (x y - w z)
_SIXD_M[[5, 15], 4] = -2.0  # 1 - 2 (x^2 + z^2)
_SIXD_M[[11, 14, 1, 4], 5] = 1.0  # 2 (y z + w x)
_SIXD_B = torch.tensor([1.0, 0.0, 0.0, 0.0, 1.0, 0.0])


# x and y of the rotated x axis as a quadratic form of the quaternion: vec(q q^T) @ M + b.
# One outer and one matrix product replace a dozen small element-wise operations, whose fixed
# per-call cost dominates at the (N, 4) size of one root per environment.
_FORWARD_M = torch.zeros(16, 2)
_FORWARD_M[[10, 15], 0] = -2.0  # fx = 1 - 2 (y^2 + z^2)
_FORWARD_M[[6, 9, 3, 12], 1] = 1.0  # fy = 2 (x y + w z), split over both symmetric entries
_FORWARD_B = torch.tensor([1.0, 0.0])

_CONSTANTS: dict[tuple[str, torch.dtype], tuple[torch.Tensor, torch.Tensor]] = {}


def _constants(name: str, dtype: torch.dtype) -> tuple[torch.Tensor, torch.Tensor]:
    """The quadratic-form matrices in ``dtype``, converted once (a conversion per call costs
    as much as the product itself at batch 1)."""
    key = (name, dtype)
    found = _CONSTANTS.get(key)
    if found is None:
        m, b = (_SIXD_M, _SIXD_B) if name == "sixd" else (_FORWARD_M, _FORWARD_B)
        found = _CONSTANTS[key] = (m.to(dtype), b.to(dtype))
    return found


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


def heading_cos_sin(q: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Cosine and sine of the heading (yaw) of orientations ``q``, without trigonometry.

    The heading is the azimuth of the body's rotated x axis projected on the ground plane. When
    that axis is vertical (a body pointed straight up) the azimuth is undefined and 0 is used,
    which keeps everything finite.
    """
    outer = (q.unsqueeze(-1) * q.unsqueeze(-2)).flatten(-2)
    m, b = _constants("forward", q.dtype)
    forward = outer @ m + b
    forward[..., 0] += 1e-12  # a vertical x axis normalises to heading 0, not to (0, 0)
    # x / max(|x|, eps), as torch.nn.functional.normalize, in three direct calls
    forward = forward / torch.linalg.vector_norm(forward, dim=-1, keepdim=True).clamp_min(1e-12)
    return forward[..., 0], forward[..., 1]


def heading_quat(q: torch.Tensor) -> torch.Tensor:
    """The yaw-only part of orientations ``q`` (see :func:`heading_cos_sin`)."""
    c, s = heading_cos_sin(q)
    # half-angle formulas: cos(a/2) = sqrt((1+c)/2), sin(a/2) = sign(s) sqrt((1-c)/2)
    half_c = torch.sqrt(((1.0 + c) * 0.5).clamp_min(0.0))
    half_s = torch.sqrt(((1.0 - c) * 0.5).clamp_min(0.0))
    half_s = torch.where(s < 0, -half_s, half_s)
    zero = torch.zeros_like(c)
    return torch.stack([half_c, zero, zero, half_s], dim=-1)


def unyaw(vectors: torch.Tensor, c: torch.Tensor, s: torch.Tensor) -> torch.Tensor:
    """Rotate vectors ``(N, ..., 3)`` by minus the yaws whose cosines/sines are ``c, s`` (N,).

    The path sensors use for positions and for the columns of 6D rotations alike: one
    ``(N, 3, 3)`` rotation built from ``c, s`` and one batched matrix product over every
    vector of an environment (fewer torch calls than rotating x and y element-wise, whose
    fixed per-call cost dominates at the batch of one a headset runs).
    """
    n = c.shape[0]
    if vectors.numel() == 0:  # no environments (or no vectors): nothing to turn
        return vectors.clone()
    zero = torch.zeros_like(c)
    # row-vector convention: v' = v @ R^T with R^T = [[c, -s, 0], [s, c, 0], [0, 0, 1]]
    rotation_t = torch.stack([c, -s, zero, s, c, zero, zero, zero, zero + 1.0], -1)
    turned = vectors.reshape(n, -1, 3) @ rotation_t.reshape(n, 3, 3).to(vectors.dtype)
    return turned.reshape(vectors.shape)


def ground_origin(root_pos: torch.Tensor, keep_height: bool = True) -> torch.Tensor:
    """Origin of the heading frame: the root's ground projection, or the root itself."""
    if keep_height:
        return torch.cat([root_pos[:, :2], torch.zeros_like(root_pos[:, 2:])], dim=-1)
    return root_pos


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
    rel = points - _per_env(ground_origin(root_pos, keep_height), points.ndim)
    return unyaw(rel, *heading_cos_sin(root_quat))


def to_heading_vectors(vectors: torch.Tensor, root_quat: torch.Tensor) -> torch.Tensor:
    """Free vectors (velocities) ``(N, ..., 3)`` in the heading frame: rotated, not moved."""
    return unyaw(vectors, *heading_cos_sin(root_quat))


def to_heading_quats(quats: torch.Tensor, root_quat: torch.Tensor) -> torch.Tensor:
    """World orientations ``(N, ..., 4)`` relative to the heading of roots ``(N, 4)``."""
    inv = quat_conj(heading_quat(root_quat))
    return quat_mul(_per_env(inv, quats.ndim), quats)
