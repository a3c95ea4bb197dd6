"""Batched rotation math in numpy (quaternions are ``wxyz``, unit length, any leading shape).

Motion data is read, resampled and retargeted on the CPU once per clip, so everything here works
on whole arrays ``(..., 4)`` / ``(..., 3, 3)`` at a time: one call per clip, never one per frame.
Rotations act on column vectors (``v' = R v``) and compose like matrices (``q1 * q2`` applies
``q2`` first).
"""

from __future__ import annotations

import numpy as np

_AXES = {"x": 0, "y": 1, "z": 2}


def normalize(q: np.ndarray) -> np.ndarray:
    """Unit quaternions with a non-negative ``w`` (one representative of the double cover)."""
    q = np.asarray(q, dtype=np.float64)
    norm = np.linalg.norm(q, axis=-1, keepdims=True)
    q = q / np.maximum(norm, 1e-12)
    return np.where(q[..., :1] < 0.0, -q, q)


def identity(shape: tuple[int, ...] = ()) -> np.ndarray:
    q = np.zeros((*shape, 4))
    q[..., 0] = 1.0
    return q


def mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product ``a * b`` (rotation ``b`` first, then ``a``), broadcasting."""
    aw, ax, ay, az = np.moveaxis(np.asarray(a, dtype=np.float64), -1, 0)
    bw, bx, by, bz = np.moveaxis(np.asarray(b, dtype=np.float64), -1, 0)
    return np.stack(
        [
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ],
        axis=-1,
    )


def conj(q: np.ndarray) -> np.ndarray:
    """Inverse of a unit quaternion."""
    q = np.asarray(q, dtype=np.float64)
    return q * np.array([1.0, -1.0, -1.0, -1.0])


def apply(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotate vectors ``v (..., 3)`` by ``q (..., 4)`` (broadcasting)."""
    q = np.asarray(q, dtype=np.float64)
    v = np.asarray(v, dtype=np.float64)
    w = q[..., :1]
    u = q[..., 1:]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def from_axis_angle(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Quaternion rotating by ``angle`` (radians) about ``axis`` (normalised here)."""
    axis = np.asarray(axis, dtype=np.float64)
    axis = axis / np.maximum(np.linalg.norm(axis, axis=-1, keepdims=True), 1e-12)
    half = 0.5 * np.asarray(angle, dtype=np.float64)[..., None]
    return np.concatenate([np.cos(half), np.sin(half) * axis], axis=-1)


def from_rotation_vector(rotvec: np.ndarray) -> np.ndarray:
    """Unit quaternions of rotation vectors ``(..., 3)`` (axis times angle), exact near zero."""
    rotvec = np.asarray(rotvec, dtype=np.float64)
    angle = np.linalg.norm(rotvec, axis=-1, keepdims=True)
    half = 0.5 * angle
    # sin(half) / angle, with its limit 1/2 at zero
    scale = np.where(angle > 1e-12, np.sin(half) / np.maximum(angle, 1e-12), 0.5)
    return np.concatenate((np.cos(half), rotvec * scale), axis=-1)


def to_rotation_vector(q: np.ndarray) -> np.ndarray:
    """Rotation vectors ``(..., 3)`` of unit quaternions, the shorter way round."""
    q = np.asarray(q, dtype=np.float64)
    q = np.where(q[..., :1] < 0, -q, q)
    v = q[..., 1:]
    s = np.linalg.norm(v, axis=-1, keepdims=True)
    angle = 2.0 * np.arctan2(s, q[..., :1])
    return v * np.where(s > 1e-12, angle / np.maximum(s, 1e-12), 2.0)


def from_euler(angles: np.ndarray, order: str, *, degrees: bool = True) -> np.ndarray:
    """Quaternion of intrinsic rotations about the axes in ``order`` (e.g. ``"zyx"``).

    BVH lists rotation channels outermost first: channels ``Zrotation Xrotation Yrotation``
    mean ``R = Rz @ Rx @ Ry``, which is exactly this function with ``order="zxy"`` and the
    angles in channel order.
    """
    angles = np.asarray(angles, dtype=np.float64)
    if degrees:
        angles = np.deg2rad(angles)
    order = order.lower()
    if len(order) != angles.shape[-1] or any(c not in _AXES for c in order):
        raise ValueError(f"bad rotation order {order!r} for {angles.shape[-1]} angles")
    q = identity(angles.shape[:-1])
    for i, axis_name in enumerate(order):
        axis = np.zeros(3)
        axis[_AXES[axis_name]] = 1.0
        q = mul(q, from_axis_angle(axis, angles[..., i]))
    return q


def to_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrices ``(..., 3, 3)`` of unit quaternions."""
    q = np.asarray(q, dtype=np.float64)
    w, x, y, z = np.moveaxis(q, -1, 0)
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        axis=-2,
    )


def from_matrix(m: np.ndarray) -> np.ndarray:
    """Unit quaternions of rotation matrices (Shepperd's method, branch-free via argmax)."""
    m = np.asarray(m, dtype=np.float64)
    m00, m11, m22 = m[..., 0, 0], m[..., 1, 1], m[..., 2, 2]
    cand = np.stack(
        [
            np.stack(
                [
                    1 + m00 + m11 + m22,
                    m[..., 2, 1] - m[..., 1, 2],
                    m[..., 0, 2] - m[..., 2, 0],
                    m[..., 1, 0] - m[..., 0, 1],
                ],
                -1,
            ),
            np.stack(
                [
                    m[..., 2, 1] - m[..., 1, 2],
                    1 + m00 - m11 - m22,
                    m[..., 0, 1] + m[..., 1, 0],
                    m[..., 0, 2] + m[..., 2, 0],
                ],
                -1,
            ),
            np.stack(
                [
                    m[..., 0, 2] - m[..., 2, 0],
                    m[..., 0, 1] + m[..., 1, 0],
                    1 - m00 + m11 - m22,
                    m[..., 1, 2] + m[..., 2, 1],
                ],
                -1,
            ),
            np.stack(
                [
                    m[..., 1, 0] - m[..., 0, 1],
                    m[..., 0, 2] + m[..., 2, 0],
                    m[..., 1, 2] + m[..., 2, 1],
                    1 - m00 - m11 + m22,
                ],
                -1,
            ),
        ],
        axis=-2,
    )
    diag = np.stack([m00 + m11 + m22, m00, m11, m22], -1)
    best = np.argmax(diag, axis=-1)
    q = np.take_along_axis(cand, best[..., None, None], axis=-2)[..., 0, :]
    return normalize(q)


def angle(q: np.ndarray) -> np.ndarray:
    """Rotation angle in radians, in ``[0, pi]``."""
    q = normalize(q)
    return 2.0 * np.arctan2(np.linalg.norm(q[..., 1:], axis=-1), np.abs(q[..., 0]))


def between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Shortest rotation taking direction ``a`` onto direction ``b`` (both ``(..., 3)``).

    Antiparallel inputs rotate by pi about an axis perpendicular to ``a``.
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    a = a / np.maximum(np.linalg.norm(a, axis=-1, keepdims=True), 1e-12)
    b = b / np.maximum(np.linalg.norm(b, axis=-1, keepdims=True), 1e-12)
    w = 1.0 + np.sum(a * b, axis=-1, keepdims=True)
    xyz = np.cross(a, b)
    # antiparallel: any axis perpendicular to a
    helper = np.where(np.abs(a[..., :1]) < 0.9, np.array([1.0, 0, 0]), np.array([0, 1.0, 0]))
    perp = np.cross(a, helper)
    anti = w < 1e-9
    xyz = np.where(anti, perp, xyz)
    w = np.where(anti, 0.0, w)
    return normalize(np.concatenate([w, xyz], axis=-1))


def slerp(q0: np.ndarray, q1: np.ndarray, t: np.ndarray | float) -> np.ndarray:
    """Spherical interpolation from ``q0`` (t=0) to ``q1`` (t=1) along the shorter arc."""
    q0 = np.asarray(q0, dtype=np.float64)
    q1 = np.asarray(q1, dtype=np.float64)
    t = np.asarray(t, dtype=np.float64)
    if t.ndim < q0.ndim:
        t = t[..., None]
    dot = np.sum(q0 * q1, axis=-1, keepdims=True)
    q1 = np.where(dot < 0, -q1, q1)
    dot = np.abs(dot)
    theta = np.arccos(np.clip(dot, -1.0, 1.0))
    sin = np.sin(theta)
    small = sin < 1e-6
    safe = np.where(small, 1.0, sin)
    w0 = np.where(small, 1.0 - t, np.sin((1.0 - t) * theta) / safe)
    w1 = np.where(small, t, np.sin(t * theta) / safe)
    return normalize(w0 * q0 + w1 * q1)


def to_6d(q: np.ndarray) -> np.ndarray:
    """Continuous 6D representation: the first two columns of the rotation matrix ``(..., 6)``.

    Networks regress rotations better in 6D than as quaternions (no double cover, no jump).
    """
    m = to_matrix(q)
    return np.concatenate([m[..., :, 0], m[..., :, 1]], axis=-1)


def from_6d(d6: np.ndarray) -> np.ndarray:
    """Quaternion from a (not necessarily orthonormal) 6D vector by Gram-Schmidt."""
    d6 = np.asarray(d6, dtype=np.float64)
    a, b = d6[..., :3], d6[..., 3:]
    x = a / np.maximum(np.linalg.norm(a, axis=-1, keepdims=True), 1e-12)
    b = b - np.sum(x * b, axis=-1, keepdims=True) * x
    y = b / np.maximum(np.linalg.norm(b, axis=-1, keepdims=True), 1e-12)
    z = np.cross(x, y)
    return from_matrix(np.stack([x, y, z], axis=-1))


def yaw(q: np.ndarray) -> np.ndarray:
    """Heading angle (about +Z) of the rotated +X axis, radians."""
    fwd = apply(q, np.array([1.0, 0.0, 0.0]))
    return np.arctan2(fwd[..., 1], fwd[..., 0])


def to_euler(q: np.ndarray, order: str, *, degrees: bool = True) -> np.ndarray:
    """Intrinsic angles in ``order`` (inverse of :func:`from_euler`, three distinct axes)."""
    order = order.lower()
    if len(order) != 3 or len(set(order)) != 3 or any(c not in _AXES for c in order):
        raise ValueError(f"to_euler needs three distinct axes, got {order!r}")
    i, j, k = (_AXES[c] for c in order)
    s = 1.0 if (j - i) % 3 == 1 else -1.0
    m = to_matrix(q)
    b = np.arcsin(np.clip(s * m[..., i, k], -1.0, 1.0))
    a = np.arctan2(-s * m[..., j, k], m[..., k, k])
    c = np.arctan2(-s * m[..., i, j], m[..., i, i])
    # gimbal lock (middle angle +-90 deg): only a +- c is defined; take c = 0 and read a from
    # R @ Rj(b)^T, which is then a pure rotation about axis i
    lock = np.abs(m[..., i, k]) > 1.0 - 1e-9
    if np.any(lock):
        axis = np.zeros(3)
        axis[j] = 1.0
        rj = to_matrix(from_axis_angle(axis, b))
        rest = m @ np.swapaxes(rj, -1, -2)
        if s > 0:
            a_lock = np.arctan2(rest[..., k, j], rest[..., j, j])
        else:
            a_lock = np.arctan2(rest[..., j, k], rest[..., k, k])
        a = np.where(lock, a_lock, a)
        c = np.where(lock, 0.0, c)
    out = np.stack([a, b, c], axis=-1)
    return np.rad2deg(out) if degrees else out
