"""Observers: contract suite, height map against analytic box heights, point cloud on surfaces."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest
import torch

from retarget.geometry.heading import yaw_quat
from retarget.plugins.observers.height_map import HeightMap, circular_grid
from retarget.plugins.observers.point_cloud import PointCloud
from retarget.plugins.scenes.boxes import Boxes, BoxSpec
from retarget.testing import parametrize_with_checks
from retarget.testing.fakes import fake_context

OBSERVERS = [HeightMap, PointCloud]


@parametrize_with_checks(OBSERVERS)
def test_observer_contract(plugin, check) -> None:
    check(plugin)


def _one_box(randomize: dict | None = None) -> Boxes:
    """A 0.4 x 0.6 x 0.2 m box centred at (1, 0)."""
    cfg = {"preset": "none", "boxes": (BoxSpec(size=(0.4, 0.6, 0.2), position=(1.0, 0.0)),)}
    cfg["randomize"] = randomize or {"position": 0.0, "yaw": 0.0}
    return Boxes(Boxes.Config(**cfg))


def _ctx(scene, root_xy: torch.Tensor, yaw: torch.Tensor, z: float = 0.9):
    n = root_xy.shape[0]
    ctx = fake_context(num_envs=n, seed=0, scene=scene)
    qpos = ctx.sim.qpos.clone()
    qpos[:, :2], qpos[:, 2] = root_xy, z
    qpos[:, 3:7] = yaw_quat(yaw)
    return replace(ctx, sim=replace(ctx.sim, qpos=qpos))


def test_paper_grid() -> None:
    grid = circular_grid(0.48, 6, 20)
    assert grid.shape == (120, 2)
    r = grid.norm(dim=-1)
    assert torch.allclose(r.max(), torch.tensor(0.48)) and torch.allclose(
        r.min(), torch.tensor(0.08)
    )
    assert HeightMap().spec(None).shape == (120,)


def _analytic(world_xy: torch.Tensor, pose: torch.Tensor) -> torch.Tensor:
    d = world_xy.double() - pose[:, None, 0, :2]
    yaw = pose[:, None, 0, 3]
    lx = torch.cos(yaw) * d[..., 0] + torch.sin(yaw) * d[..., 1]
    ly = -torch.sin(yaw) * d[..., 0] + torch.cos(yaw) * d[..., 1]
    inside = (lx.abs() <= 0.2) & (ly.abs() <= 0.3)
    return torch.where(inside, 0.2, 0.0)


@pytest.mark.parametrize("randomize", [None, {"position": 0.08, "yaw": 0.1}])
def test_height_map_equals_box_heights(randomize) -> None:
    scene = _one_box(randomize)
    n = 4
    scene.allocate(n)
    scene.randomize(torch.arange(n), torch.Generator().manual_seed(0))
    root = torch.tensor([[0.7, 0.0], [1.0, 0.1], [0.6, -0.2], [5.0, 5.0]])
    yaw = torch.tensor([0.0, math.pi / 2, -0.7, 1.0])
    obs = HeightMap()
    ctx = _ctx(scene, root, yaw)
    h = obs.observe(ctx)
    # the grid in world coordinates, by hand: rotate heading-frame offsets by each yaw
    g = circular_grid(0.48, 6, 20)
    c, s = torch.cos(yaw)[:, None], torch.sin(yaw)[:, None]
    world = torch.stack(
        [root[:, :1] + c * g[:, 0] - s * g[:, 1], root[:, 1:] + s * g[:, 0] + c * g[:, 1]], -1
    )
    expected = _analytic(world, scene.placement()).float()
    assert torch.allclose(h, expected, atol=1e-6)
    assert h[0].max() == pytest.approx(0.2) and h[3].abs().max() == 0.0
    # facing the box (env 0, yaw 0, 0.3 m before it): the points ahead see it, those behind not
    ahead = g[:, 0] > 0.35
    if randomize is None:  # a moved box may put the far edge anywhere near 0.48 m
        assert (h[0, ahead & (g[:, 1].abs() < 0.05)] == 0.2).all() and (
            h[0, g[:, 0] < 0] == 0
        ).all()


def test_height_map_relative_modes() -> None:
    scene = _one_box()
    root, yaw = torch.tensor([[1.0, 0.0]]), torch.zeros(1)
    ctx = _ctx(scene, root, yaw, z=1.1)
    world = HeightMap().observe(ctx)
    ground = HeightMap(HeightMap.Config(relative="ground")).observe(ctx)
    rel_root = HeightMap(HeightMap.Config(relative="root")).observe(ctx)
    assert torch.allclose(ground, world - 0.2) and torch.allclose(rel_root, world - 1.1)


def test_height_map_turns_with_the_character() -> None:
    scene = _one_box()
    a = HeightMap().observe(_ctx(scene, torch.tensor([[0.7, 0.0]]), torch.zeros(1)))
    # the same relative situation, rotated: box ahead of a character facing +y
    other = Boxes(
        Boxes.Config(
            preset="none",
            boxes=(BoxSpec(size=(0.4, 0.6, 0.2), position=(0.0, 1.0), yaw=math.pi / 2),),
            randomize={"position": 0.0, "yaw": 0.0},
        )
    )
    b = HeightMap().observe(_ctx(other, torch.tensor([[0.0, 0.7]]), torch.tensor([math.pi / 2])))
    assert torch.allclose(a, b, atol=1e-6)


def test_point_cloud_points_lie_on_surfaces_near_the_root() -> None:
    scene = _one_box({"position": 0.08, "yaw": 0.1})
    n = 3
    scene.allocate(n)
    scene.randomize(torch.arange(n), torch.Generator().manual_seed(1))
    root = torch.tensor([[0.6, 0.0], [1.0, 0.5], [4.0, 0.0]])
    yaw = torch.tensor([0.3, -1.0, 0.0])
    obs = PointCloud(PointCloud.Config(count=300, pool=4000))
    ctx = _ctx(scene, root, yaw, z=0.5)
    out = obs.observe(ctx)
    assert out.shape == (n, 300, 4)
    mask = out[..., 3] > 0
    assert mask[0].sum() > 50 and mask[2].sum() == 0
    assert (out[~mask] == 0).all()
    # back to the world frame
    c, s = torch.cos(yaw)[:, None], torch.sin(yaw)[:, None]
    x, y, z = out[..., 0], out[..., 1], out[..., 2]
    wx, wy = root[:, :1] + c * x - s * y, root[:, 1:] + s * x + c * y
    world = torch.stack([wx, wy, z], -1)
    dist = (world - torch.cat([root, torch.full((n, 1), 0.5)], 1)[:, None]).norm(dim=-1)
    assert (dist[mask] <= 1.0 + 1e-5).all()
    # on the placed box's surface: inside it and on a face
    pose = scene.placement().float()
    d = world[..., :2] - pose[:, None, 0, :2]
    py = pose[:, None, 0, 3]
    lx = torch.cos(py) * d[..., 0] + torch.sin(py) * d[..., 1]
    ly = -torch.sin(py) * d[..., 0] + torch.cos(py) * d[..., 1]
    local = torch.stack([lx, ly, z - 0.1], -1).abs()
    half = torch.tensor([0.2, 0.3, 0.1])
    inside = (local <= half + 1e-4).all(-1)
    face = ((local - half).abs() < 1e-4).any(-1)
    assert (inside & face)[mask].all()


def test_point_cloud_follows_a_reset_envs_new_placement() -> None:
    scene = _one_box({"position": 0.08, "yaw": 0.1})
    n = 2
    scene.allocate(n)
    obs = PointCloud(PointCloud.Config(count=200, pool=2000))
    ctx = _ctx(scene, torch.tensor([[0.8, 0.0], [0.8, 0.0]]), torch.zeros(2))
    first = obs.observe(ctx)
    assert torch.equal(first[0], first[1])  # same placement, same samples
    scene.randomize(torch.tensor([1]), torch.Generator().manual_seed(2))
    obs.reset(torch.tensor([1]))
    second = obs.observe(ctx)
    assert torch.equal(second[0], first[0]) and not torch.equal(second[1], first[1])


def _full_scan(pool: torch.Tensor, root: torch.Tensor, yaw: torch.Tensor, k: int, radius: float):
    """The point cloud by brute force: every pool point tested, the first ``k`` in range kept."""
    n = pool.shape[0]
    out = torch.zeros(n, k, 4)
    c, s = torch.cos(yaw), torch.sin(yaw)
    for e in range(n):
        rel = pool[e] - root[e]
        rows = rel[rel.norm(dim=-1) <= radius][:k]
        x, y = c[e] * rows[:, 0] + s[e] * rows[:, 1], -s[e] * rows[:, 0] + c[e] * rows[:, 1]
        out[e, : len(rows)] = torch.stack([x, y, rows[:, 2] + root[e, 2], torch.ones(len(rows))], 1)
    return out


def test_point_cloud_chunk_prefilter_equals_a_full_scan() -> None:
    from retarget.plugins.scenes.living_room import LivingRoom

    scene = LivingRoom(LivingRoom.Config())
    n = 6
    scene.allocate(n)
    scene.randomize(torch.arange(n), torch.Generator().manual_seed(3))
    g = torch.Generator().manual_seed(4)
    cfg = PointCloud.Config(count=400, pool=3000, chunk=32)
    obs = PointCloud(cfg)
    import numpy as np

    def pool() -> torch.Tensor:
        return torch.from_numpy(scene.surface_points(cfg.pool, np.random.default_rng(cfg.seed)))

    for step in range(4):
        if step == 3:  # two environments reset to new placements: their pools are re-placed
            scene.randomize(torch.tensor([1, 4]), torch.Generator().manual_seed(5))
            obs.reset(torch.tensor([1, 4]))
        root = torch.rand(n, 2, generator=g) * 4 - 2
        yaw = torch.rand(n, generator=g) * 6
        ctx = _ctx(scene, root, yaw, z=0.6)
        got = obs.observe(ctx)
        root3 = torch.cat([root, torch.full((n, 1), 0.6)], 1)
        want = _full_scan(pool().float(), root3, yaw, cfg.count, cfg.radius)
        assert got[..., 3].sum() > 100  # the draw reaches props
        assert torch.equal(got[..., 3], want[..., 3])
        assert torch.allclose(got, want, atol=1e-5)
