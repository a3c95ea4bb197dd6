"""Each reward term against a value computed by hand on a controlled step."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest
import torch

from retarget import PluginError
from retarget.geometry.heading import yaw_quat
from retarget.plugins.rewards.action import ActionDiff, ActionMin
from retarget.plugins.rewards.contact import FootContact
from retarget.plugins.rewards.fail import FailPenalty
from retarget.plugins.rewards.joint import JointPos, JointVel
from retarget.plugins.rewards.link import LinkPos, LinkVel
from retarget.plugins.rewards.orientation import Orientation
from retarget.testing import fake_context, tiny_world


def _ctx(n: int = 2, layout=None):
    """A step whose simulated state equals the reference (every imitation distance is 0)."""
    layout = layout or tiny_world().layout
    ctx = fake_context(layout, n, seed=1)
    return replace(ctx, sim=ctx.ref.pose)


def _with_sim(ctx, **changes):
    return replace(ctx, sim=replace(ctx.sim, **changes))


def _value(term, ctx) -> torch.Tensor:
    term.bind(ctx.layout)
    out = term.compute(ctx)
    assert out.dtype == torch.float32 and out.shape == (ctx.num_envs,)
    return out


def test_joint_pos_weighted_squared_angles() -> None:
    layout = replace(tiny_world().layout, joint_weights=(2.0, 1.0, 1.0, 1.0, 1.0, 0.5))
    ctx = _ctx(layout=layout)
    qpos = ctx.sim.qpos.clone()
    qpos[0, 7] += 0.1  # spine, weight 2
    qpos[0, 12] += 0.2 + 2 * math.pi  # tail, weight 0.5, wrapped once around
    ctx = _with_sim(ctx, qpos=qpos)
    d = 2 * 0.1**2 + 0.5 * 0.2**2  # 0.04
    out = _value(JointPos(), ctx)
    torch.testing.assert_close(out, torch.tensor([math.exp(-25 * d), 1.0]))
    mean = _value(JointPos(JointPos.Config(reduce="mean")), ctx)
    torch.testing.assert_close(mean, torch.tensor([math.exp(-25 * d / 6.5), 1.0]))


def test_joint_pos_ignores_root() -> None:
    ctx = _ctx()
    qpos = ctx.sim.qpos.clone()
    qpos[:, :7] += 1.0
    assert torch.allclose(_value(JointPos(), _with_sim(ctx, qpos=qpos)), torch.ones(2))


def test_joint_vel_squared_velocity_error() -> None:
    ctx = _ctx()
    qvel = ctx.sim.qvel.clone()
    qvel[1, 6] += 1.0
    qvel[1, 9] -= 0.5
    qvel[:, :6] += 3.0  # root velocities are not joints
    out = _value(JointVel(), _with_sim(ctx, qvel=qvel))
    torch.testing.assert_close(out, torch.tensor([1.0, math.exp(-1.0 * 1.25)]))


def test_link_pos_selected_bodies() -> None:
    ctx = _ctx()
    pos = ctx.sim.body_pos.clone()
    pos[0, 0, 0] += 0.1  # pelvis (root)
    pos[0, 4, 2] += 0.2  # left_leg (feet)
    pos[0, 1, 1] += 5.0  # torso: not selected
    ctx = _with_sim(ctx, body_pos=pos)
    out = _value(LinkPos(LinkPos.Config(bodies=["root", "feet", "left_leg"])), ctx)
    torch.testing.assert_close(out, torch.tensor([math.exp(-6 * 0.05), 1.0]))
    every = _value(LinkPos(), ctx)
    torch.testing.assert_close(every, torch.tensor([math.exp(-6 * 25.05), 1.0]))


def test_link_pos_root_relative_ignores_a_shifted_pose() -> None:
    ctx = _ctx()
    ctx = _with_sim(ctx, body_pos=ctx.sim.body_pos + torch.tensor([1.0, -2.0, 0.3]))
    assert torch.allclose(_value(LinkPos(LinkPos.Config(root_relative=True)), ctx), torch.ones(2))
    assert (_value(LinkPos(), ctx) < 1e-3).all()


def test_link_pos_unknown_body_names_the_choices() -> None:
    with pytest.raises(PluginError, match="upper_body"):
        LinkPos(LinkPos.Config(bodies=["nose"])).bind(tiny_world().layout)


def test_link_vel_squared_velocity_error() -> None:
    ctx = _ctx()
    vel = ctx.sim.body_linvel.clone()
    vel[1, 2] += torch.tensor([0.3, 0.4, 0.0])  # |dv| = 0.5
    out = _value(LinkVel(LinkVel.Config(bodies=["left_arm"])), _with_sim(ctx, body_linvel=vel))
    torch.testing.assert_close(out, torch.tensor([1.0, math.exp(-2 * 0.25)]))


def test_orientation_root_and_head_angles() -> None:
    ctx = _ctx()
    head = tiny_world().layout.site("head")
    identity = torch.tensor([1.0, 0.0, 0.0, 0.0])
    qpos_sim, qpos_ref = ctx.sim.qpos.clone(), ctx.sim.qpos.clone()
    site_sim, site_ref = ctx.sim.site_quat.clone(), ctx.sim.site_quat.clone()
    qpos_sim[:, 3:7] = identity
    qpos_ref[:, 3:7] = yaw_quat(torch.tensor([0.3, 0.0]))
    site_sim[:, head] = identity
    half = 0.25  # 0.5 rad about x
    site_ref[:, head] = torch.tensor([math.cos(half), math.sin(half), 0.0, 0.0])
    site_ref[1, head] = -site_ref[1, head]  # the same rotation, other sign
    ref = replace(ctx.ref, pose=replace(ctx.ref.pose, qpos=qpos_ref, site_quat=site_ref))
    ctx = replace(ctx, sim=replace(ctx.sim, qpos=qpos_sim, site_quat=site_sim), ref=ref)
    out = _value(Orientation(), ctx)
    torch.testing.assert_close(out, torch.tensor([math.exp(-3 * 0.8), math.exp(-3 * 0.5)]))
    root_only = _value(Orientation(Orientation.Config(head_weight=0.0)), ctx)
    torch.testing.assert_close(root_only, torch.tensor([math.exp(-0.9), 1.0]))


def test_foot_contact_per_body_mismatches() -> None:
    ctx = _ctx(3)
    force = torch.zeros_like(ctx.sim.contact_force)
    force[:, 4] = torch.tensor([0.5, 2.0, 2.0])  # left_leg: off, on, on
    force[:, 5] = torch.tensor([2.0, 2.0, 0.0])  # right_leg: on, on, off
    labels = torch.tensor([[True, True], [True, True], [True, True]])
    ctx = replace(_with_sim(ctx, contact_force=force), ref=replace(ctx.ref, contacts=labels))
    out = _value(FootContact(), ctx)
    torch.testing.assert_close(out, torch.tensor([math.exp(-1), 1.0, math.exp(-1)]))
    frac = _value(FootContact(FootContact.Config(normalize=True)), ctx)
    torch.testing.assert_close(frac, torch.tensor([math.exp(-0.5), 1.0, math.exp(-0.5)]))


def test_foot_contact_left_right_labels_over_several_foot_bodies() -> None:
    base = tiny_world().layout
    groups = {"feet": (4, 5, 2, 3), "left_foot": (4, 2), "right_foot": (5, 3), "upper_body": (1,)}
    layout = replace(base, body_groups=groups)
    ctx = _ctx(2, layout=layout)
    force = torch.zeros_like(ctx.sim.contact_force)
    force[0, 2] = 5.0  # env 0: the left foot touches through its second body only
    labels = torch.tensor([[True, False], [False, True]])
    ctx = replace(_with_sim(ctx, contact_force=force), ref=replace(ctx.ref, contacts=labels))
    out = _value(FootContact(FootContact.Config(k=2.0)), ctx)
    torch.testing.assert_close(out, torch.tensor([1.0, math.exp(-2.0)]))
    bad = replace(ctx, ref=replace(ctx.ref, contacts=torch.zeros(2, 3, dtype=torch.bool)))
    with pytest.raises(PluginError, match="3 reference contact labels"):
        _value(FootContact(), bad)


def test_fail_penalty_applies_on_failed_envs_only() -> None:
    term = FailPenalty()
    failed = replace(_ctx(3), terminated=torch.tensor([True, False, True]))
    torch.testing.assert_close(_value(term, failed), torch.tensor([-5.0, 0.0, -5.0]))
    assert torch.equal(_value(term, replace(failed, terminated=None)), torch.zeros(3))


def test_action_terms_mean_squared_actions() -> None:
    ctx = _ctx(2)
    nu = ctx.layout.nu
    action = torch.full((2, nu), 0.5)
    action[1] = 0.0
    prev = torch.zeros(2, nu)
    prev[1, :2] = 1.0  # env 1: mean diff^2 = 2 / nu
    ctx = replace(ctx, action=action, prev_action=prev)
    diff = _value(ActionDiff(), ctx)
    torch.testing.assert_close(diff, torch.tensor([math.exp(-10 * 0.25), math.exp(-10 * 2 / nu)]))
    small = _value(ActionMin(), ctx)
    torch.testing.assert_close(small, torch.tensor([math.exp(-25 * 0.25), 1.0]))


def test_defaults_are_the_human_column_of_table_2() -> None:
    expected = {
        JointPos: (4.0, 25.0),
        JointVel: (0.5, 1.0),
        LinkPos: (2.5, 6.0),
        LinkVel: (0.7, 2.0),
        Orientation: (2.0, 3.0),
        FootContact: (0.0, 1.0),
        ActionDiff: (1.5, 10.0),
        ActionMin: (0.5, 25.0),
    }
    for cls, (w, k) in expected.items():
        config = cls.Config()
        assert (config.weight, config.k) == (w, k), cls.name
    assert FailPenalty.Config().value == -5.0
