"""Teacher sensors: the full reference body ahead (PHC's goal state) and the reference's joint
targets as PD actions, on fake steps and in a real environment."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest
import torch
from helpers import TINY

from retarget.env.build import env_from_recipe
from retarget.geometry.heading import quat_mul, yaw_quat
from retarget.plugins.sensors.full_body import FullBody
from retarget.recipe import load, parse_text, resolve
from retarget.registry.loader import load_plugins
from retarget.testing import fake_context, tiny_world

LAYOUT = tiny_world().layout


def test_no_difference_when_the_simulated_body_is_the_reference() -> None:
    ctx = fake_context(LAYOUT, 5, seed=3, future_offsets=(1,))
    same = replace(ctx, ref=replace(ctx.ref, future={1: ctx.sim}))
    sensor = FullBody()
    sensor.bind(LAYOUT)
    out = sensor.observe(same)
    b = LAYOUT.num_bodies
    per = out[:, :-3].reshape(5, b, 24)
    identity6 = torch.tensor([1.0, 0, 0, 0, 1, 0])  # 6D of the identity rotation (two columns)
    assert torch.allclose(per[..., :6], identity6.expand(5, b, 6), atol=1e-5)
    assert per[..., 6:15].abs().max() < 1e-6  # position and velocity differences
    assert out[:, -3:].abs().max() < 1e-6  # root offset
    moved = replace(ctx, ref=replace(ctx.ref, future={1: ctx.ref.pose}))
    assert (sensor.observe(moved) - out).abs().max() > 0.1


def test_full_body_is_invariant_to_where_and_which_way_the_pair_stands() -> None:
    ctx = fake_context(LAYOUT, 4, seed=1, future_offsets=(1, 3))
    sensor = FullBody(FullBody.Config(offsets=[1, 3]))
    sensor.bind(LAYOUT)
    before = sensor.observe(ctx)
    q = yaw_quat(torch.tensor(0.7))
    shift = torch.tensor([2.0, -1.0, 0.0])

    def turn(state):
        pos = torch.einsum("ij,...j->...i", _rot(0.7), state.body_pos) + shift
        qpos = state.qpos.clone()
        qpos[:, :3] = torch.einsum("ij,nj->ni", _rot(0.7), qpos[:, :3]) + shift
        qpos[:, 3:7] = quat_mul(q.expand(4, 4), qpos[:, 3:7])
        rot = lambda v: torch.einsum("ij,...j->...i", _rot(0.7), v)  # noqa: E731
        return replace(state, qpos=qpos, body_pos=pos, body_quat=quat_mul(
            q.expand_as(state.body_quat), state.body_quat),
            body_linvel=rot(state.body_linvel), body_angvel=rot(state.body_angvel))

    turned = replace(ctx, sim=turn(ctx.sim), ref=replace(
        ctx.ref, future={k: turn(v) for k, v in ctx.ref.future.items()}))
    assert torch.allclose(sensor.observe(turned), before, atol=1e-4)
    assert before.shape == (4, 2 * (24 * LAYOUT.num_bodies + 3))


def _rot(a: float) -> torch.Tensor:
    c, s = math.cos(a), math.sin(a)
    return torch.tensor([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def test_config_refuses_offsets_that_are_not_ahead() -> None:
    with pytest.raises(ValueError, match="offsets"):
        FullBody.Config(offsets=[0])
    with pytest.raises(ValueError, match="offsets"):
        FullBody.Config(offsets=[1, 1])


def test_reference_action_in_a_real_env_is_the_next_reference_pose() -> None:
    registry = load_plugins()
    recipe = TINY.replace("sensors: [three_point]", "sensors: [reference_action]")
    resolved = resolve(parse_text(recipe.replace("sim: {threads: 1}",
                                                 "sim: {threads: 1, actuation: pd}"),
                                  "tiny.yaml", ".yaml"), registry)  # fmt: skip
    env = env_from_recipe(resolved)
    obs = env.reset()
    layout = env.layout
    rows = env.library.rows(env.clip, env.frame, (1,))[:, 0]
    q_next = env.reference.qpos[rows][:, list(layout.actuator_qpos)]
    scale = torch.tensor(layout.actuator_ranges).abs().amax(-1)
    cols = slice(0, layout.nu)
    expected = (q_next / scale).clamp(-1, 1)
    assert torch.allclose(obs["actor"][:, cols], expected, atol=1e-5)
    # a PD target of that action drives every joint toward the reference's next angle
    q0 = env.sim.state.qpos[:, list(layout.actuator_qpos)].clone()
    env.step(obs["actor"][:, cols])
    q1 = env.sim.state.qpos[:, list(layout.actuator_qpos)]
    closer = ((q1 - q_next).abs() <= (q0 - q_next).abs() + 0.02).float().mean()
    assert closer > 0.8
    assert load(None, registry).recipe.sim.actuation == "pd", "the packaged default is PD"
