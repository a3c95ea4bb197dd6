"""Scenes recorded with their clips: boxes read from a mesh beside a clip, an episode that
sees only its own clip's props, props at the character's scale, reference contact labels
against each clip's own props; and the real box-climb captures (skipped without them)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import torch
import trimesh
from helpers import REPO

from retarget.env import RetargetEnv
from retarget.motion import skeleton as sk
from retarget.motion.procedural import default_motions
from retarget.motion.shared_data import shared_data
from retarget.registry.loader import load_plugins
from retarget.scene.mesh_boxes import boxes_from_mesh
from retarget.settings.env import EnvOptions

BOX_CLIMB = shared_data("scenes/box_climb")
NAMES = REPO / "examples" / "layouts" / "box_climb_joints.txt"


Box = tuple[tuple[float, float], float, tuple[float, float], float]  # centre, yaw, size, top


def _box_mesh(path: Path, boxes: list[Box]) -> Path:
    parts = []
    for (x, y), yaw, (sx, sy), h in boxes:
        m = trimesh.creation.box(extents=(sx, sy, h))
        turn = trimesh.transformations.rotation_matrix(yaw, (0, 0, 1))
        m.apply_transform(turn)
        m.apply_translation((x, y, h / 2))
        parts.append(m)
    trimesh.util.concatenate(parts).export(path)
    return path


def test_boxes_come_back_from_a_mesh(tmp_path) -> None:
    path = _box_mesh(tmp_path / "s.obj", [((1.0, 2.0), 0.3, (1.0, 0.5), 0.47),
                                          ((-1.0, 0.0), 0.0, (0.6, 0.6), 0.18)])  # fmt: skip
    got = sorted(boxes_from_mesh(path), key=lambda b: b.height)
    assert [round(b.height, 3) for b in got] == [0.18, 0.47]
    tall = got[1]
    assert np.allclose(tall.position, (1.0, 2.0), atol=1e-6)
    assert abs(tall.yaw - 0.3) < 1e-6 and np.allclose(tall.size, (1.0, 0.5), atol=1e-6)
    assert abs(got[0].fill - 1.0) < 1e-6


def _clips_with_meshes(tmp_path: Path):
    """Two generated walks in their own folders, each with its own mesh of boxes."""
    walk = default_motions(names=("walk",))[0]
    clips = []
    for k, spot in enumerate(((2.0, 0.0), (2.0, 3.0))):
        folder = tmp_path / f"take{k}"
        folder.mkdir()
        _box_mesh(folder / "boxes.obj", [(spot, 0.0, (0.5, 0.5), 0.3)])
        shared = (-3.0, -3.0)
        _box_mesh(folder / "boxes.obj", [(spot, 0.0, (0.5, 0.5), 0.3),
                                         (shared, 0.0, (0.5, 0.5), 0.6)])  # fmt: skip
        clips.append(walk.with_(name=f"take{k}", source=folder / f"take{k}.npz"))
    return clips


def test_per_clip_props_park_the_other_clips_boxes(tmp_path) -> None:
    registry = load_plugins()
    scene_cls = registry.get("scene", "motion_props").cls
    character = registry.get("character", "human").cls()
    scene = scene_cls(scene_cls.Config(per_clip=True, auto=False,
                                       randomize={"position": 0.0, "yaw": 0.0}))  # fmt: skip
    env = RetargetEnv(character, _clips_with_meshes(tmp_path), scene=scene,
                      options=EnvOptions(num_envs=4))  # fmt: skip
    fitted = scene.fitted
    assert len(fitted) == 3, "the identical 0.6 m box of both clips is one shared prop"
    env.place(torch.tensor([0, 1, 0, 1]), torch.zeros(4, dtype=torch.long))
    placed = scene.placement()[:2]  # (2 envs, props, 4)
    spots = [tuple(np.round(s.position, 2)) for s in fitted]
    own = {0: spots.index((2.0, 0.0)), 1: spots.index((2.0, 3.0))}
    shared = spots.index((-3.0, -3.0))
    for env_id, clip in ((0, 0), (1, 1)):
        assert torch.allclose(placed[env_id, own[clip], :2].float(),
                              torch.tensor(spots[own[clip]]).float(), atol=1e-6)  # fmt: skip
        other = own[1 - clip]
        assert placed[env_id, other, :2].abs().min() > 40, "another clip's box is parked"
        assert placed[env_id, shared, :2].abs().max() < 4
    # each clip's reference is labelled against its own boxes only
    assert scene.reference_placement(0)[0][own[1], 0] < -40


def test_props_given_in_the_clip_frame_follow_the_characters_scale(tmp_path) -> None:
    registry = load_plugins()
    scene_cls = registry.get("scene", "motion_props").cls
    dino = registry.get("character", "dino").cls()
    scene = scene_cls(scene_cls.Config(auto=False))
    clips = _clips_with_meshes(tmp_path)[:1]
    env = RetargetEnv(dino, clips, scene=scene, options=EnvOptions(num_envs=2))
    ratio = env.reference.qpos64[0, 2] / clips[0].root_pos[0, 2]  # the reference's root scale
    low = min(scene.fitted, key=lambda s: s.height)
    assert low.height == pytest.approx(0.3 * ratio, rel=0.02)
    assert low.position[0] == pytest.approx(2.0 * ratio, rel=0.02)


needs_box_climb = pytest.mark.skipif(
    not (BOX_CLIMB / "seq_0").is_dir(),
    reason=f"the box-climb captures are not at {BOX_CLIMB} (set RETARGET_SHARED_DATA)",
)


@needs_box_climb
def test_a_box_climb_capture_loads_with_its_boxes_and_stands_on_them() -> None:
    from retarget.env.build import env_from_recipe
    from retarget.recipe import load

    registry = load_plugins()
    seq = BOX_CLIMB / "seq_0"
    resolved = load(REPO / "examples" / "recipes" / "box_climb_teacher.yaml", registry,
                    shorthands={"motions": str(seq)},
                    assignments=[f"motions.format.joints={NAMES}"])  # fmt: skip
    env = env_from_recipe(resolved, num_envs=2, threads=1, registry=registry)
    assert env.library.num_clips == 1 and abs(int(env.library.length[0]) - 2800 / 120 * 36) < 2
    assert len(env.scene.fitted) == 3
    groups = list(env.layout.body_groups)
    feet = [groups.index("left_foot"), groups.index("right_foot")]
    tall = max(s.height for s in env.scene.fitted)
    on_top = env.reference.qpos64[:, 2] > tall + 0.8  # the pelvis above the tall box's top
    assert on_top.sum() > 30, "the capture stands on the tall box"
    labels = env.reference.scene_contacts[torch.from_numpy(on_top)][:, feet]
    assert labels.any(-1).float().mean() > 0.8, "a foot touches the box top while up there"
    deep, _ = env.sim.pose_penetration(env.reference.qpos64[on_top])
    assert np.median(deep) < 0.03, "feet rest on the top, not in it"
    toe = env.library.global_pos[torch.from_numpy(on_top)][:, sk.TOES[0], 2]
    assert float(toe.median()) > 0.8
