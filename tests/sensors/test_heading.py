"""The batched rotation helpers agree with matrix algebra and define a yaw-free frame."""

from __future__ import annotations

import math

import torch

from retarget.geometry.heading import (
    heading_cos_sin,
    heading_quat,
    quat_angle,
    quat_apply,
    quat_conj,
    quat_mul,
    quat_normalize,
    quat_to_6d,
    quat_to_matrix,
    rotation_distance,
    to_heading_points,
    to_heading_quats,
    to_heading_vectors,
    yaw_quat,
)


def _quats(*shape: int, seed: int = 0) -> torch.Tensor:
    return quat_normalize(torch.randn(*shape, 4, generator=torch.Generator().manual_seed(seed)))


def test_apply_and_multiply_match_matrices() -> None:
    a, b = _quats(6), _quats(6, seed=1)
    v = torch.randn(6, 3)
    ra, rb = quat_to_matrix(a), quat_to_matrix(b)
    torch.testing.assert_close(quat_apply(a, v), torch.einsum("nij,nj->ni", ra, v))
    torch.testing.assert_close(quat_to_matrix(quat_mul(a, b)), ra @ rb)
    torch.testing.assert_close(quat_mul(a, quat_conj(a)), torch.tensor([1.0, 0, 0, 0]).expand(6, 4))
    torch.testing.assert_close(torch.linalg.det(ra), torch.ones(6))


def test_six_d_is_first_two_columns() -> None:
    q = _quats(5)
    m = quat_to_matrix(q)
    torch.testing.assert_close(quat_to_6d(q), torch.cat([m[:, :, 0], m[:, :, 1]], dim=-1))


def test_angle_and_distance() -> None:
    q = yaw_quat(torch.tensor([0.0, 0.4, -2.0, math.pi]))
    torch.testing.assert_close(quat_angle(q), torch.tensor([0.0, 0.4, 2.0, math.pi]))
    torch.testing.assert_close(quat_angle(-q), quat_angle(q))
    a, b = _quats(8), _quats(8, seed=2)
    rel = quat_to_matrix(a) @ quat_to_matrix(b).transpose(-1, -2)
    cos = ((rel.diagonal(dim1=-2, dim2=-1).sum(-1) - 1) / 2).clamp(-1, 1)
    torch.testing.assert_close(rotation_distance(a, b), torch.acos(cos), atol=1e-4, rtol=1e-4)


def test_heading_removes_only_yaw() -> None:
    q = _quats(16)
    h = heading_quat(q)
    assert torch.allclose(h[:, 1:3], torch.zeros(16, 2))
    local = quat_mul(quat_conj(h), q)  # what is left after removing the yaw
    forward = quat_apply(local, torch.tensor([1.0, 0.0, 0.0]).expand(16, 3))
    torch.testing.assert_close(forward[:, 1], torch.zeros(16), atol=1e-5, rtol=0)
    assert (forward[:, 0] >= -1e-6).all()


def test_heading_frame_of_a_turned_root() -> None:
    root_pos = torch.tensor([[1.0, 2.0, 0.9]])
    root_quat = yaw_quat(torch.tensor([math.pi / 2]))  # facing +y
    point = torch.tensor([[[1.0, 3.0, 1.7]]])  # one metre ahead of the root
    torch.testing.assert_close(
        to_heading_points(point, root_pos, root_quat), torch.tensor([[[1.0, 0.0, 1.7]]])
    )
    torch.testing.assert_close(
        to_heading_points(point, root_pos, root_quat, keep_height=False),
        torch.tensor([[[1.0, 0.0, 0.8]]]),
    )
    torch.testing.assert_close(
        to_heading_vectors(torch.tensor([[[0.0, 2.0, 0.5]]]), root_quat),
        torch.tensor([[[2.0, 0.0, 0.5]]]),
    )
    torch.testing.assert_close(
        to_heading_quats(root_quat[:, None], root_quat), torch.tensor([[[1.0, 0.0, 0.0, 0.0]]])
    )


def test_heading_of_a_vertical_body_is_finite() -> None:
    pitch_up = torch.tensor([[math.cos(math.pi / 4), 0.0, -math.sin(math.pi / 4), 0.0]])
    c, s = heading_cos_sin(pitch_up)  # x axis points straight up: heading undefined
    assert torch.isfinite(c).all() and torch.isfinite(s).all()
    torch.testing.assert_close(c * c + s * s, torch.ones(1))
