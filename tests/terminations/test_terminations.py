"""Fall and root-distance terminations on controlled steps."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import torch

from retarget.plugins.terminations.episode_cap import EpisodeCap
from retarget.plugins.terminations.fall import Fall
from retarget.plugins.terminations.root_distance import RootDistance
from retarget.scene.ground import Ground
from retarget.testing import FlatScene, fake_context, tiny_world

LAYOUT = tiny_world().layout
TORSO, LEFT_ARM, LEFT_LEG = 1, 2, 4  # torso/arms form the tiny character's upper_body


def _check(term, ctx) -> torch.Tensor:
    term.bind(ctx.layout)
    out = term.check(ctx)
    assert out.dtype == torch.bool and out.shape == (ctx.num_envs,)
    return out


def _standing(n: int):
    """Every body 1 m up and touching nothing."""
    ctx = fake_context(LAYOUT, n, seed=0)
    pos = ctx.sim.body_pos.clone()
    pos[..., 2] = 1.0
    sim = replace(ctx.sim, body_pos=pos, contact_force=torch.zeros_like(ctx.sim.contact_force))
    return replace(ctx, sim=sim)


def _set(ctx, env: int, body: int, height: float, force: float):
    pos, f = ctx.sim.body_pos.clone(), ctx.sim.contact_force.clone()
    pos[env, body, 2] = height
    f[env, body] = force
    return replace(ctx, sim=replace(ctx.sim, body_pos=pos, contact_force=f))


def test_fall_needs_an_upper_body_touching_low() -> None:
    ctx = _standing(5)
    ctx = _set(ctx, 0, TORSO, 0.1, 20.0)  # torso on the floor: fallen
    ctx = _set(ctx, 1, TORSO, 0.1, 0.5)  # low but not pressing: not fallen
    ctx = _set(ctx, 2, LEFT_ARM, 1.0, 20.0)  # arm touching something high (a table)
    ctx = _set(ctx, 3, LEFT_LEG, 0.05, 500.0)  # a foot on the floor is walking
    ctx = _set(ctx, 4, LEFT_ARM, 0.2, 3.0)  # hand/arm down on the floor
    assert _check(Fall(), ctx).tolist() == [True, False, False, False, True]
    strict = Fall(Fall.Config(force_threshold=5.0, height_threshold=0.15))
    assert _check(strict, ctx).tolist() == [True, False, False, False, False]


class RaisedFloor(FlatScene):
    """Ground 0.8 m up everywhere (a stage)."""

    name = "raised_test"

    def height_at(self, xy: torch.Tensor) -> torch.Tensor:
        return torch.full(xy.shape[:-1], 0.8)

    def surface_points(self, count: int, rng: np.random.Generator) -> np.ndarray:
        return np.zeros((count, 3))


def test_fall_measures_height_above_the_scene_ground() -> None:
    ctx = _set(_standing(2), 0, TORSO, 0.9, 20.0)
    ctx = _set(ctx, 1, TORSO, 0.1, 20.0)
    assert _check(Fall(), ctx).tolist() == [False, True]
    assert _check(Fall(), replace(ctx, scene=RaisedFloor())).tolist() == [True, True]
    assert _check(Fall(), replace(ctx, scene=Ground())).tolist() == [False, True]


def test_root_distance_threshold() -> None:
    ctx = fake_context(LAYOUT, 4, seed=3)
    qpos = ctx.ref.pose.qpos.clone()
    qpos[:, :3] += torch.tensor(
        [[0.29, 0.0, 0.0], [0.0, 0.31, 0.0], [0.2, 0.2, 0.2], [0.0, 0.1, 0.5]]
    )
    ctx = replace(ctx, sim=replace(ctx.sim, qpos=qpos))
    assert _check(RootDistance(), ctx).tolist() == [False, True, True, True]
    flat = RootDistance(RootDistance.Config(horizontal=True))
    assert _check(flat, ctx).tolist() == [False, True, False, False]
    assert not RootDistance.time_out and not Fall.time_out and EpisodeCap.time_out
