"""Scenes: contract suite, analytic heights, surface points, per-env randomization, meshes."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest
import torch
import trimesh

from retarget.errors import PluginError
from retarget.plugins.characters.human import Human
from retarget.plugins.scenes.bench import Bench
from retarget.plugins.scenes.boxes import Boxes, BoxSpec
from retarget.plugins.scenes.chair import Chair
from retarget.plugins.scenes.couch import Couch
from retarget.plugins.scenes.flat import Flat
from retarget.plugins.scenes.living_room import LivingRoom
from retarget.plugins.scenes.mesh import MeshScene
from retarget.plugins.scenes.rotating_chair import RotatingChair
from retarget.plugins.scenes.stool import Stool
from retarget.plugins.scenes.tilting_chair import TiltingChair
from retarget.registry.loader import load_plugins
from retarget.sim.world import build_world
from retarget.testing import parametrize_with_checks

SCENES = [
    Flat,
    Boxes,
    Chair,
    Stool,
    Bench,
    Couch,
    TiltingChair,
    RotatingChair,
    LivingRoom,
    MeshScene,
]


@parametrize_with_checks(SCENES)
def test_scene_contract(plugin, check) -> None:
    check(plugin)


def test_every_scene_is_installed() -> None:
    names = set(load_plugins(strict=True).entries["scene"])
    assert {s.name for s in SCENES} <= names


def _box_scene(randomize: dict | None = None) -> Boxes:
    """Two boxes: 0.4 x 0.6 x 0.2 at (1, 0) and 0.5 x 0.5 x 0.3 at (-1, 1) turned by 45 deg."""
    boxes = (
        BoxSpec(size=(0.4, 0.6, 0.2), position=(1.0, 0.0), yaw=0.0),
        BoxSpec(size=(0.5, 0.5, 0.3), position=(-1.0, 1.0), yaw=math.pi / 4),
    )
    cfg = {"preset": "none", "boxes": boxes}
    if randomize is not None:
        cfg["randomize"] = randomize
    return Boxes(Boxes.Config(**cfg))


def _analytic(xy: torch.Tensor, pose: torch.Tensor) -> torch.Tensor:
    """Heights of the two boxes placed at ``pose`` ``(N, 2, 4)`` (x, y, z, yaw)."""
    sizes = torch.tensor([[0.4, 0.6, 0.2], [0.5, 0.5, 0.3]], dtype=torch.float64)
    out = torch.zeros(xy.shape[:2], dtype=torch.float64)
    for b in range(2):
        d = xy.double() - pose[:, None, b, :2]
        yaw = pose[:, None, b, 3]
        lx = torch.cos(yaw) * d[..., 0] + torch.sin(yaw) * d[..., 1]
        ly = -torch.sin(yaw) * d[..., 0] + torch.cos(yaw) * d[..., 1]
        inside = (lx.abs() <= sizes[b, 0] / 2) & (ly.abs() <= sizes[b, 1] / 2)
        out = torch.maximum(out, torch.where(inside, sizes[b, 2] + pose[:, None, b, 2], 0.0))
    return out


def test_box_heights_match_geometry() -> None:
    scene = _box_scene()
    probes = torch.tensor(
        [[1.0, 0.0], [1.19, 0.29], [1.21, 0.0], [-1.0, 1.0], [-1.0 + 0.34, 1.0], [0.0, 0.0]]
    )
    h = scene.height_at(probes[None])
    # the rotated box's corner reaches 0.354 m along x; 0.34 is inside it
    assert torch.allclose(h[0], torch.tensor([0.2, 0.2, 0.0, 0.3, 0.3, 0.0]))


def test_box_heights_follow_each_envs_randomization() -> None:
    scene = _box_scene({"position": 0.08, "yaw": 0.1})
    n = 6
    scene.allocate(n)
    scene.randomize(torch.arange(n), torch.Generator().manual_seed(3))
    xy = torch.rand(n, 400, 2, generator=torch.Generator().manual_seed(4)) * 3 - 1.5
    pose = scene.placement()
    h = scene.height_at(xy)
    assert torch.allclose(h.double(), _analytic(xy, pose), atol=1e-6)
    # the box edge moves with the placement: some probes change height between envs
    same = scene.height_at(xy[:1].expand(n, -1, -1))
    assert not torch.equal(same[0], same[1])


def test_randomization_bounds_and_differs_between_envs() -> None:
    scene = LivingRoom(LivingRoom.Config(randomize={"position": 0.08, "yaw": 0.1}))
    n = 64
    scene.allocate(n)
    base = scene.placement().clone()
    scene.randomize(torch.arange(n), torch.Generator().manual_seed(0))
    off = scene.placement() - base
    assert (off[..., :2].norm(dim=-1) <= 0.08 + 1e-9).all()
    assert (off[..., 3].abs() <= 0.1 + 1e-9).all()
    assert (off[..., 2] == 0).all()
    assert off[..., :2].norm(dim=-1).max() > 0.06 and off[..., 3].abs().max() > 0.08
    assert not torch.allclose(off[0], off[1])
    before = scene.placement().clone()
    scene.randomize(torch.tensor([5]), torch.Generator().manual_seed(9))
    changed = (scene.placement() != before).any(dim=-1).any(dim=-1)
    assert changed.nonzero().flatten().tolist() == [5]
    pos, quat = scene.mocap_poses(torch.tensor([5, 7]))
    assert torch.allclose(pos, scene.placement()[[5, 7], :, :3])
    assert torch.allclose(
        2 * torch.atan2(quat[..., 3], quat[..., 0]), scene.placement()[[5, 7], :, 3]
    )


def test_randomization_off() -> None:
    scene = Chair(Chair.Config(randomize={"position": 0.0, "yaw": 0.0}))
    scene.allocate(3)
    scene.randomize(torch.arange(3), torch.Generator().manual_seed(0))
    assert (scene.placement() == scene.placement()[:1]).all()


@pytest.mark.parametrize("cls", [Boxes, Chair, Stool, Bench, Couch, RotatingChair])
def test_surface_points_lie_on_the_geometry(cls) -> None:
    """Every point is on some part's surface in its env's placement: inside or on the part's
    box/cylinder with at least one coordinate on its boundary."""
    scene = cls()
    n = 3
    scene.allocate(n)
    scene.randomize(torch.arange(n), torch.Generator().manual_seed(1))
    pts = torch.from_numpy(scene.surface_points(500, np.random.default_rng(2)))
    pose = scene.placement()
    on_any = torch.zeros(n, 500, dtype=torch.bool)
    for prop_index, part in scene._tables.parts:
        p = pose[:, None, prop_index]
        d = pts[..., :2] - p[..., :2]
        c, s = torch.cos(p[..., 3]), torch.sin(p[..., 3])
        local = torch.stack(
            [
                c * d[..., 0] + s * d[..., 1],
                -s * d[..., 0] + c * d[..., 1],
                pts[..., 2] - p[..., 2],
            ],
            -1,
        ) - torch.tensor(part.pos, dtype=torch.float64)
        half = torch.tensor(part.half, dtype=torch.float64)
        eps = 1e-6
        if part.shape == "box":
            inside = (local.abs() <= half + eps).all(-1)
            boundary = ((local.abs() - half).abs() < eps).any(-1)
        else:
            r = local[..., :2].norm(dim=-1)
            inside = (r <= half[0] + eps) & (local[..., 2].abs() <= half[2] + eps)
            boundary = ((r - half[0]).abs() < eps) | ((local[..., 2].abs() - half[2]).abs() < eps)
        on_any |= inside & boundary
    assert on_any.all()
    assert (pts[..., 2] > 1e-9).all(), "no point on the floor under a prop"


def test_height_at_rejects_a_mismatched_batch() -> None:
    scene = Chair()
    scene.allocate(4)
    with pytest.raises(PluginError, match="chair"):
        scene.height_at(torch.zeros(3, 5, 2))


def test_hinged_props_are_articulated() -> None:
    for cls, axis in ((TiltingChair, [0, 1, 0]), (RotatingChair, [0, 0, 1])):
        world = build_world(Human(), cls())
        m = world.model
        assert m.nq == world.layout.nq + 1 and m.nv == world.layout.nv + 1
        jid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, f"scene_{cls.name}_hinge")
        assert jid >= 0 and np.allclose(m.jnt_axis[jid], axis)
        moving = m.jnt_bodyid[jid]
        assert 5.0 < m.body_mass[moving] < 15.0  # seat and backrest of wood-like density
    tilt = build_world(Human(), TiltingChair()).model
    jid = mujoco.mj_name2id(tilt, mujoco.mjtObj.mjOBJ_JOINT, "scene_tilting_chair_hinge")
    assert tilt.jnt_stiffness[jid] > 0 and tilt.dof_damping[tilt.jnt_dofadr[jid]] > 0


# ---------------------------------------------------------------- meshes


def _write_room(path) -> None:
    """A 4 x 4 m floor slab, a wall and a 40 cm step, written with trimesh."""
    import trimesh

    parts = [
        trimesh.creation.box([4.0, 4.0, 0.02]).apply_translation([0, 0, -0.01]),
        trimesh.creation.box([0.1, 4.0, 1.0]).apply_translation([1.9, 0, 0.5]),
        trimesh.creation.box([0.6, 0.6, 0.4]).apply_translation([1.0, 1.0, 0.2]),
    ]
    trimesh.util.concatenate(parts).export(path)


@pytest.mark.parametrize("collision", ["heightfield", "hulls"])
def test_mesh_room_holds_a_standing_human(tmp_path, collision: str) -> None:
    path = tmp_path / "room.obj"
    _write_room(path)
    scene = MeshScene(MeshScene.Config(path=str(path), collision=collision))
    heights = scene.height_at(torch.tensor([[[1.0, 1.0], [0.0, 0.0], [1.9, -1.0], [3.0, 3.0]]]))
    assert torch.allclose(heights, torch.tensor([[0.4, 0.0, 1.0, 0.0]]), atol=1e-6)
    world = build_world(Human(), scene)
    m = world.model
    m.opt.timestep = 1 / 360
    data = mujoco.MjData(m)
    mujoco.mj_resetData(m, data)  # qpos0: the character's standing rest pose
    data.qpos[:2] = [-0.5, -0.5]
    body = np.asarray(world.layout.body_ids)
    for _ in range(720):  # 2 s with zero torque
        mujoco.mj_step(m, data)
    assert np.isfinite(data.qpos).all() and np.isfinite(data.qvel).all()
    assert data.xpos[body, 2].min() > 0.0, "a body went through the floor"
    assert (data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number) == 0
    pts = scene.surface_points(200, np.random.default_rng(0))
    assert pts.shape == (1, 200, 3) and (np.abs(pts[..., :2]) <= 2.0 + 1e-9).all()


def test_mesh_errors_name_the_file(tmp_path) -> None:
    bad = tmp_path / "broken.obj"
    bad.write_text("this is not an obj\n")
    for path in (tmp_path / "missing.glb", bad):
        with pytest.raises(PluginError) as err:
            MeshScene(MeshScene.Config(path=str(path)))
        assert path.name in str(err.value) and "mesh" in str(err.value)


def _flat_platform(path) -> None:
    verts = np.array([[0, 0, 0.3], [2, 0, 0.3], [2, 1, 0.3], [0, 1, 0.3]], dtype=float)
    trimesh.Trimesh(verts, np.array([[0, 1, 2], [0, 2, 3]])).export(path)


@pytest.mark.parametrize("collision", ["heightfield", "hulls"])
def test_a_flat_mesh_is_a_valid_scene(tmp_path, collision: str) -> None:
    path = tmp_path / "platform.obj"
    _flat_platform(path)
    scene = MeshScene(MeshScene.Config(path=str(path), collision=collision))
    heights = scene.height_at(torch.tensor([[[1.0, 0.5], [5.0, 5.0]]]))
    torch.testing.assert_close(heights, torch.tensor([[0.3, 0.0]]), atol=1e-3, rtol=0)
    build_world(Human(), scene)


def test_mesh_limits_are_stated_in_the_error(tmp_path) -> None:
    path = tmp_path / "platform.obj"
    _flat_platform(path)
    with pytest.raises(PluginError, match=r"2000 m across .* at most 1000 m"):
        MeshScene(MeshScene.Config(path=str(path), scale=1000.0))
    with pytest.raises(PluginError, match=r"height grid would have .* \(at most 2,000,000\)"):
        MeshScene(MeshScene.Config(path=str(path), scale=200.0))
    with pytest.raises(PluginError, match="non-finite"):  # 2 * 1e308 overflows
        MeshScene(MeshScene.Config(path=str(path), scale=1e308))
