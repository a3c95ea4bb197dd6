"""Headset and three-point sensors: layout of the observation, window selection, invariance."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest
import torch

from retarget import PluginError
from retarget.geometry.heading import quat_apply, quat_mul, quat_to_6d, yaw_quat
from retarget.plugins.sensors.devices import ControllerTracking, Hmd, ThreePoint
from retarget.testing import fake_context, tiny_world

LAYOUT = tiny_world().layout
ALL_SENSORS = [
    Hmd(),
    Hmd(Hmd.Config(past=2, future=1, keep_height=False)),
    ThreePoint(),
    ThreePoint(ThreePoint.Config(past=1, future=2)),
    ThreePoint(ThreePoint.Config(past=2, controller_rotation=False)),
]


def _observe(sensor, ctx) -> torch.Tensor:
    sensor.bind(ctx.layout)
    out = sensor.observe(ctx)
    assert out.shape == (ctx.num_envs, *sensor.spec(ctx.layout).shape)
    assert out.dtype == torch.float32
    return out


def _at_origin(ctx):
    """The simulated root at the origin facing +x: the heading frame is the world frame."""
    qpos = ctx.sim.qpos.clone()
    qpos[:, :3] = torch.tensor([0.0, 0.0, 0.9])
    qpos[:, 3:7] = torch.tensor([1.0, 0.0, 0.0, 0.0])
    return replace(ctx, sim=replace(ctx.sim, qpos=qpos))


def test_sizes() -> None:
    # defaults: the previous and the current reading (paper Eq. 2)
    assert Hmd().spec(LAYOUT).shape == (2 * 9,)
    assert ThreePoint().spec(LAYOUT).shape == (2 * 27,)
    assert ThreePoint(ThreePoint.Config(past=0)).spec(LAYOUT).shape == (27,)
    no_rotation = ThreePoint.Config(past=0, controller_rotation=False)
    assert ThreePoint(no_rotation).spec(LAYOUT).shape == (15,)
    assert ThreePoint(ThreePoint.Config(past=2, future=1)).spec(LAYOUT).shape == (4 * 27,)


def test_controller_tracking_gives_each_controllers_flag_per_frame() -> None:
    ctx = _at_origin(fake_context(LAYOUT, 3, seed=4))  # window offsets -2..2
    sensor = ControllerTracking(ControllerTracking.Config(past=1))
    assert sensor.spec(LAYOUT).shape == (2 * 2,)
    assert (_observe(sensor, ctx) == 1).all()  # a reference without flags: every one tracked
    tracked = torch.ones(3, 5, 3, dtype=torch.bool)
    tracked[1, 2, 2] = False  # environment 1: the right controller lost now (offset 0)
    tracked[2, 0, 1] = False  # environment 2: the left one lost before the window
    tracked[0, 3, 0] = False  # a headset flag is not a controller's
    lost = replace(ctx, ref=replace(ctx.ref, devices_tracked=tracked))
    flags = torch.ones(3, 2, 2)  # (environment, frame: -1 then 0, left / right)
    flags[1, 1, 1] = 0.0
    assert torch.equal(_observe(sensor, lost).reshape(3, 2, 2), flags)
    ahead = ControllerTracking(ControllerTracking.Config(past=0, future=2))
    assert torch.equal(_observe(ahead, lost).reshape(3, 3, 2)[:, 0], flags[:, 1])
    assert torch.equal(_observe(ThreePoint(), lost), _observe(ThreePoint(), ctx))  # poses only


def test_values_in_world_aligned_frame() -> None:
    ctx = _at_origin(fake_context(LAYOUT, 3, seed=4))  # window offsets -2..2
    dev = ctx.ref.devices
    out = _observe(ThreePoint(ThreePoint.Config(past=1, future=1)), ctx).reshape(3, 3, 3, 9)
    frames = dev[:, 1:4]  # offsets -1, 0, 1
    torch.testing.assert_close(out[..., :3], frames[..., :3])
    torch.testing.assert_close(out[..., 3:], quat_to_6d(frames[..., 3:]))
    pos_only = _observe(ThreePoint(ThreePoint.Config(past=0, controller_rotation=False)), ctx)
    now = dev[:, 2]
    expected = torch.cat(
        [now[:, 0, :3], quat_to_6d(now[:, 0, 3:]), now[:, 1, :3], now[:, 2, :3]], 1
    )
    torch.testing.assert_close(pos_only, expected)
    torch.testing.assert_close(_observe(Hmd(Hmd.Config(past=0)), ctx), expected[:, :9])
    two = _observe(Hmd(), ctx)  # default: previous reading, then the current one
    torch.testing.assert_close(two[:, 9:], expected[:, :9])
    torch.testing.assert_close(two[:, :3], dev[:, 1, 0, :3])


def test_values_follow_the_root_heading() -> None:
    ctx = _at_origin(fake_context(LAYOUT, 2, seed=6))
    qpos = ctx.sim.qpos.clone()
    qpos[:, :2] = torch.tensor([3.0, -1.0])
    qpos[:, 3:7] = yaw_quat(torch.full((2,), math.pi / 2))
    ctx = replace(ctx, sim=replace(ctx.sim, qpos=qpos))
    hmd = ctx.ref.devices[:, 2, 0]
    x, y, z = hmd[:, 0] - 3.0, hmd[:, 1] + 1.0, hmd[:, 2]
    out = _observe(Hmd(Hmd.Config(past=0)), ctx)
    torch.testing.assert_close(out[:, :3], torch.stack([y, -x, z], dim=-1))


def test_missing_window_frames_are_an_error() -> None:
    ctx = fake_context(LAYOUT, 2, window_offsets=(-1, 0))
    with pytest.raises(PluginError, match=r"lacks frame offsets \[-2\]"):
        _observe(Hmd(Hmd.Config(past=2)), ctx)
    with pytest.raises(PluginError, match=r"lacks frame offsets \[1\]"):
        _observe(ThreePoint(ThreePoint.Config(future=1)), ctx)


def _move_world(ctx, yaw: torch.Tensor, shift: torch.Tensor):
    """Rotate everything about the vertical axis by ``yaw`` (N,) and translate by ``shift``."""
    q = yaw_quat(yaw)  # (N, 4)

    def points(p: torch.Tensor) -> torch.Tensor:
        qb = q.reshape(q.shape[0], *([1] * (p.ndim - 2)), 4)
        s = shift.reshape(shift.shape[0], *([1] * (p.ndim - 2)), 3)
        return quat_apply(qb, p) + s

    def quats(r: torch.Tensor) -> torch.Tensor:
        return quat_mul(q.reshape(q.shape[0], *([1] * (r.ndim - 2)), 4), r)

    def state(s):
        qpos = s.qpos.clone()
        qpos[:, :3] = points(s.qpos[:, :3])
        qpos[:, 3:7] = quats(s.qpos[:, 3:7])
        return replace(
            s,
            qpos=qpos,
            body_pos=points(s.body_pos),
            body_quat=quats(s.body_quat),
            site_pos=points(s.site_pos),
            site_quat=quats(s.site_quat),
        )

    dev = ctx.ref.devices
    devices = torch.cat([points(dev[..., :3]), quats(dev[..., 3:])], dim=-1)
    ref = replace(ctx.ref, pose=state(ctx.ref.pose), devices=devices)
    return replace(ctx, sim=state(ctx.sim), ref=ref)


@pytest.mark.parametrize("sensor", ALL_SENSORS, ids=repr)
def test_heading_frame_invariance(sensor) -> None:
    ctx = fake_context(LAYOUT, 6, seed=9)
    g = torch.Generator().manual_seed(3)
    yaw = torch.rand(6, generator=g) * 2 * math.pi - math.pi
    shift = torch.randn(6, 3, generator=g) * 5.0
    shift[:, 2] = 0.0  # horizontal only: heights above the floor are observed
    before = _observe(sensor, ctx)
    after = _observe(type(sensor)(sensor.config), _move_world(ctx, yaw, shift))
    torch.testing.assert_close(after, before, atol=1e-4, rtol=1e-4)
    assert not torch.allclose(_move_world(ctx, yaw, shift).ref.devices, ctx.ref.devices)


def test_vertical_shift_is_seen_unless_relative_to_root() -> None:
    ctx = fake_context(LAYOUT, 3, seed=2)
    up = _move_world(ctx, torch.zeros(3), torch.tensor([0.0, 0.0, 0.5]).expand(3, 3))
    assert not torch.allclose(_observe(Hmd(), up), _observe(Hmd(), ctx))
    relative = Hmd(Hmd.Config(keep_height=False))
    torch.testing.assert_close(_observe(relative, up), _observe(relative, ctx))


def test_window_in_any_order() -> None:
    ctx = _at_origin(fake_context(LAYOUT, 2, seed=5, window_offsets=(0, -1, 2, 1)))
    out = _observe(Hmd(Hmd.Config(past=1, future=1)), ctx).reshape(2, 3, 9)
    frames = ctx.ref.devices[:, [1, 0, 3], 0]  # offsets -1, 0, 1
    torch.testing.assert_close(out[..., :3], frames[..., :3])
