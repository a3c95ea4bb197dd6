"""Training samples of a kinematic pose estimator: device windows in, the human body out.

A pose estimator (EnvPoser, EgoPoser) has no simulated body, so everything is expressed in
the frame a headset application has: the **headset frame**, the current headset's ground
projection turned to its heading (heights stay world heights). The inputs are the run's own
sensor plugins computed as if the character's root were the headset (their heading-frame
transform then is exactly this frame), so an estimator and a policy read the same device
features. The target is the canonical skeleton (:mod:`retarget.motion.skeleton`): the root's
position and rotation in the headset frame and every joint's local rotation, plus the two
foot contacts; positions come from forward kinematics with the average adult's proportions at
the clip's height, so position errors measure the pose, not bone lengths.

Mirroring (left and right swapped, reflected through the headset's XZ plane) doubles the data
for free, in tensor operations on the batch.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import torch

from retarget.geometry.heading import (
    ground_origin,
    heading_cos_sin,
    heading_quat,
    quat_conj,
    quat_mul,
    quat_to_matrix,
    unyaw,
)
from retarget.kinds import Sensor
from retarget.kinds.state import ReferenceBatch, StepContext
from retarget.motion import skeleton as sk

J = sk.NUM_JOINTS
PARENTS = sk.PARENTS
UNIT_OFFSETS = torch.tensor(sk.rest_offsets(1.0), dtype=torch.float32)
"""Bone offsets ``(J, 3)`` of a 1 m tall average adult: times the height, the skeleton used."""
_LR = torch.tensor(sk.LEFT_RIGHT, dtype=torch.long)
_FLIP_POS = torch.tensor([1.0, -1.0, 1.0])
_FLIP_QUAT = torch.tensor([1.0, -1.0, 1.0, -1.0])


def sixd_to_matrix(x: torch.Tensor) -> torch.Tensor:
    """Rotation matrices ``(..., 3, 3)`` from 6D vectors (the first two columns, as
    :func:`retarget.geometry.heading.quat_to_6d` lays them out), by Gram-Schmidt."""
    a = torch.nn.functional.normalize(x[..., 0:3], dim=-1, eps=1e-8)
    b = x[..., 3:6] - (a * x[..., 3:6]).sum(-1, keepdim=True) * a
    b = torch.nn.functional.normalize(b, dim=-1, eps=1e-8)
    return torch.stack([a, b, torch.cross(a, b, dim=-1)], dim=-1)


def matrix_to_6d(m: torch.Tensor) -> torch.Tensor:
    return torch.cat([m[..., :, 0], m[..., :, 1]], dim=-1)


def forward_kinematics(
    root_pos: torch.Tensor, local: torch.Tensor, heights: torch.Tensor
) -> torch.Tensor:
    """Joint positions ``(B, J, 3)`` of root positions ``(B, 3)``, local rotation matrices
    ``(B, J, 3, 3)`` and body heights ``(B,)`` (average proportions)."""
    return forward_kinematics_globals(root_pos, local, heights)[0]


def forward_kinematics_globals(
    root_pos: torch.Tensor, local: torch.Tensor, heights: torch.Tensor
) -> tuple[torch.Tensor, list[torch.Tensor]]:
    """Joint positions ``(B, J, 3)`` and each joint's global rotation matrix ``(B, 3, 3)``
    on the average skeleton at ``heights`` ``(B,)``."""
    return skeleton_globals(root_pos, local, UNIT_OFFSETS.to(root_pos) * heights[:, None, None])


def skeleton_globals(
    root_pos: torch.Tensor, local: torch.Tensor, offsets: torch.Tensor
) -> tuple[torch.Tensor, list[torch.Tensor]]:
    """:func:`forward_kinematics_globals` on a skeleton of its own: bone offsets ``(B, J, 3)``
    (a person's, as a motion file gives them, where the average proportions would misplace
    the joints by centimetres)."""
    pos: list[torch.Tensor] = [root_pos]
    glob: list[torch.Tensor] = [local[:, 0]]
    for j in range(1, J):
        p = PARENTS[j]
        pos.append(pos[p] + (glob[p] @ offsets[:, j, :, None])[..., 0])
        glob.append(glob[p] @ local[:, j])
    return torch.stack(pos, dim=1), glob


@dataclass(frozen=True)
class HeadsetFrame:
    """The headset frame of a batch: ground origin ``(B, 3)``, heading as cos/sin and quat."""

    origin: torch.Tensor
    cos: torch.Tensor
    sin: torch.Tensor
    yaw: torch.Tensor  # (B, 4) wxyz, rotation about +Z only

    @classmethod
    def of(cls, headset: torch.Tensor) -> HeadsetFrame:
        """From current headset poses ``(B, 7)``."""
        c, s = heading_cos_sin(headset[:, 3:7])
        return cls(ground_origin(headset[:, :3]), c, s, heading_quat(headset[:, 3:7]))

    def points_in(self, world: torch.Tensor) -> torch.Tensor:
        shape = (world.shape[0],) + (1,) * (world.ndim - 2) + (3,)
        return unyaw(world - self.origin.reshape(shape), self.cos, self.sin)

    def points_out(self, local: torch.Tensor) -> torch.Tensor:
        """World points of headset-frame points ``(B, ..., 3)``."""
        shape = (local.shape[0],) + (1,) * (local.ndim - 2) + (3,)
        return unyaw(local, self.cos, -self.sin) + self.origin.reshape(shape)

    def quat_in(self, q: torch.Tensor) -> torch.Tensor:
        return quat_mul(quat_conj(self.yaw), q)

    def quat_in_many(self, q: torch.Tensor) -> torch.Tensor:
        """``quat_in`` of quaternions ``(B, K, 4)``, K per sample."""
        k = q.shape[1]
        return quat_mul(quat_conj(self.yaw)[:, None].expand(-1, k, -1), q)

    def poses_in(self, poses: torch.Tensor) -> torch.Tensor:
        """Device poses ``(B, K, 7)`` (world position, wxyz) in this frame, K per sample."""
        return torch.cat([self.points_in(poses[..., :3]), self.quat_in_many(poses[..., 3:7])], -1)

    def quat_out(self, q: torch.Tensor) -> torch.Tensor:
        return quat_mul(self.yaw, q)


def mirror_devices(devices: torch.Tensor) -> torch.Tensor:
    """Device poses ``(..., 3, 7)`` reflected through the world XZ plane, controllers swapped."""
    swapped = devices[..., [0, 2, 1], :]
    return torch.cat([swapped[..., :3] * _FLIP_POS, swapped[..., 3:] * _FLIP_QUAT], dim=-1)


def mirror_body(
    root_pos: torch.Tensor, local_rot: torch.Tensor, contacts: torch.Tensor
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """The canonical pose ``(B, 3)``, ``(B, J, 4)``, contacts ``(B, 2)`` mirrored the same way."""
    return root_pos * _FLIP_POS, local_rot[:, _LR] * _FLIP_QUAT, contacts.flip(-1)


@dataclass(frozen=True)
class PoseTargets:
    """What the estimator should output, in the headset frame."""

    root_pos: torch.Tensor  # (B, 3)
    rot6d: torch.Tensor  # (B, J, 6): root rotation relative to the heading, then local
    positions: torch.Tensor  # (B, J, 3) joint positions by forward kinematics
    contacts: torch.Tensor  # (B, 2) float 0/1
    heights: torch.Tensor  # (B,)


def sensor_inputs(
    env, rows: torch.Tensor, mirrored: torch.Tensor | None = None,
    scale: torch.Tensor | None = None, frozen_from: torch.Tensor | None = None,
):  # fmt: skip
    """Inputs ``(B, D)`` of the env's sensors at library ``rows`` ``(B,)`` in the headset
    frame, and that frame. ``mirrored`` ``(B,)`` bool reflects those samples' devices;
    ``scale`` ``(B,)`` makes each sample's person that much taller (positions scale about the
    world origin, so the same motion by a larger or smaller person); ``frozen_from``
    ``(B, 2)`` holds each controller (left, right) still from that entry of the window on (an
    index past the window: not at all), as a headset runtime reports a hand that left its
    cameras' view."""
    lib = env.library
    clip = torch.searchsorted(lib.start, rows, right=True) - 1
    frame = rows - lib.start[clip]
    window = lib.rows(clip, frame, env.window_offsets)
    devices = lib.devices[window]  # (B, W, 3, 7)
    if mirrored is not None and bool(mirrored.any()):
        devices = torch.where(mirrored[:, None, None, None], mirror_devices(devices), devices)
    if scale is not None:
        devices = torch.cat([devices[..., :3] * scale[:, None, None, None], devices[..., 3:]], -1)
    w = devices.shape[1]
    if frozen_from is not None and bool((frozen_from < w).any()):
        start = frozen_from.clamp(max=w - 1)  # (B, 2)
        held = torch.gather(devices[:, :, 1:], 1, start[:, None, :, None].expand(-1, 1, -1, 7))
        after = torch.arange(w)[None, :, None] >= frozen_from[:, None, :]  # (B, W, 2)
        devices = devices.clone()
        devices[:, :, 1:] = torch.where(after[..., None], held, devices[:, :, 1:])
    return device_features(env, rows, devices)


def device_features(env, rows: torch.Tensor, devices: torch.Tensor):
    """:func:`sensor_inputs` of given device windows ``(B, W, 3, 7)`` (world) at library
    ``rows`` (the body and scene of those rows, for sensors that read more than devices)."""
    lib = env.library
    clip = torch.searchsorted(lib.start, rows, right=True) - 1
    frame = rows - lib.start[clip]
    now = devices[:, env.window_offsets.index(0), 0]
    frame_of = HeadsetFrame.of(now)
    pose = env.reference.pose(rows)
    qpos = pose.qpos.clone()
    qpos[:, :3], qpos[:, 3:7] = now[:, :3], frame_of.yaw
    sim = replace(pose, qpos=qpos)
    ref = ReferenceBatch(pose=pose, devices=devices, window_offsets=tuple(env.window_offsets),
                         contacts=lib.contacts[rows], rows=rows)  # fmt: skip
    b, nu = rows.shape[0], len(env.layout.actuator_names)
    zeros = torch.zeros(b, nu)
    ctx = StepContext(layout=env.layout, sim=sim, ref=ref, action=zeros, prev_action=zeros,
                      episode_step=torch.zeros(b, dtype=torch.long), dt=1.0 / lib.fps,
                      scene=env.scene)  # fmt: skip
    sensors: list[Sensor] = list(env.sensors)
    parts = [s.observe(ctx).reshape(b, -1).float() for s in sensors]
    if env.observers:  # the scene around the user, each sample with its own clip's props
        ctx = replace(ctx, scene=_scene_for(env.scene, clip, frame, lib.fps))
        parts += [o.observe(ctx).reshape(b, -1).float() for o in env.observers]
    return torch.cat(parts, dim=-1), frame_of


def reads_controllers(env) -> bool:
    """Whether the env's sensors read the controllers: their features at the library's first
    frame change when both controllers move 10 cm. An estimator from the headset alone has
    none to reach, and must not take them from the library."""
    lib, first = env.library, torch.zeros(1, dtype=torch.long)
    rows = lib.start[:1].clone()
    devices = lib.devices[lib.rows(first, first, env.window_offsets)]
    moved = devices.clone()
    moved[:, :, 1:, :3] += 0.1
    a, _ = device_features(env, rows, devices)
    b, _ = device_features(env, rows, moved)
    return not torch.equal(a, b)


def _scene_for(scene, clip: torch.Tensor, frame: torch.Tensor, fps: float):
    """The env's scene holding one placement per sample: where each sample's clip puts its
    props (per-clip props, boxes on a path), with the scene's usual noise from a fixed seed.
    The estimator never steps the env, so its scene's placement state is free to use."""
    ids = torch.arange(clip.shape[0])
    scene.allocate(int(clip.shape[0]))
    scene.start_episodes(ids, clip, frame.double() / fps)
    scene.randomize(ids, torch.Generator().manual_seed(0))
    return scene


def pose_targets(
    env, rows: torch.Tensor, frame: HeadsetFrame, mirrored: torch.Tensor | None = None,
    scale: torch.Tensor | None = None,
) -> PoseTargets:  # fmt: skip
    """The reference body at ``rows`` in the headset ``frame`` (mirrored and scaled as the
    inputs were)."""
    lib = env.library
    root_pos, local_rot = lib.root_pos[rows], lib.local_rot[rows]
    contacts = lib.contacts[rows].float()
    if mirrored is not None and bool(mirrored.any()):
        m_pos, m_rot, m_con = mirror_body(root_pos, local_rot, contacts)
        root_pos = torch.where(mirrored[:, None], m_pos, root_pos)
        local_rot = torch.where(mirrored[:, None, None], m_rot, local_rot)
        contacts = torch.where(mirrored[:, None], m_con, contacts)
    clip = torch.searchsorted(lib.start, rows, right=True) - 1
    heights = lib.heights[clip].float()
    if scale is not None:
        root_pos, heights = root_pos * scale[:, None], heights * scale
    local_rot = local_rot.clone()
    local_rot[:, 0] = frame.quat_in(local_rot[:, 0])
    root = frame.points_in(root_pos)
    mats = quat_to_matrix(local_rot)
    return PoseTargets(root, matrix_to_6d(mats), forward_kinematics(root, mats, heights),
                       contacts, heights)  # fmt: skip
