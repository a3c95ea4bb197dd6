"""``path_boxes``: boxes drawn per episode on the walking path of the clip each env plays."""

from __future__ import annotations

import torch

from retarget.env import EnvOptions, RetargetEnv
from retarget.motion.procedural import default_motions
from retarget.plugins.characters.human import Human
from retarget.plugins.scenes.flat import Flat
from retarget.plugins.scenes.path_boxes import PARK, PathBoxes
from tests.scenes.test_scene_env import make_env

WALK, TURN = default_motions(names=("walk", "turn_left"))


def _env(num_envs: int = 16, **config) -> RetargetEnv:
    scene = PathBoxes(PathBoxes.Config(**config))
    return RetargetEnv(Human(), [WALK, TURN], scene=scene, options=EnvOptions(num_envs=num_envs))


def test_boxes_lie_ahead_on_each_envs_path_with_heights_in_range() -> None:
    env = _env(lateral=0.1, clear=0.6)
    env.reset()
    pose = env.scene.placement()  # (N, K, 4)
    lib = env.library
    # the character's own reference root path (what the env plays), not the scene's copy
    root = env.reference.qpos64[:, :2]
    for i in range(env.num_envs):
        c, f = int(env.clip[i]), int(env.frame[i])
        rows = int(lib.start[c]) + torch.arange(f, int(lib.length[c]))
        path = torch.as_tensor(root[rows.numpy()])
        start = torch.as_tensor(root[int(lib.start[c]) + f])
        for x, y, _, _ in pose[i].tolist():
            if x < PARK[0] + 10:  # parked: no room ahead (a start near the clip's end)
                continue
            assert (path - torch.tensor([x, y])).norm(dim=-1).min() < 0.1 + 0.05
            assert (torch.tensor([x, y]) - start).norm() > 0.6 - 0.05
    placed = pose[..., 0] > PARK[0] + 10
    assert placed.float().mean() > 0.5
    # the height map sees each placed box's top at a height in [5, 25] cm
    top = env.scene.height_at(pose[..., :2].float())
    assert ((top[placed] >= 0.05 - 1e-4) & (top[placed] <= 0.25 + 1e-4)).all()
    assert top[placed].std() > 0.02  # heights vary


def test_boxes_are_redrawn_every_episode_and_park_without_room() -> None:
    env = _env(num_envs=4)
    env.reset()
    first = env.scene.placement().clone()
    env.reset()
    assert not torch.allclose(first, env.scene.placement())
    last = env.library.length[:1].repeat(4) - 3  # starts at the walk's very end
    env.place(torch.zeros(4, dtype=torch.long), last)
    assert (env.scene.placement()[..., 0] < PARK[0] + 10).all()


def test_reference_contact_labels_are_those_of_flat_ground() -> None:
    boxes = _env(num_envs=2)
    flat = RetargetEnv(Human(), [WALK, TURN], scene=Flat(), options=EnvOptions(num_envs=2))
    assert torch.equal(boxes.reference.scene_contacts, flat.reference.scene_contacts)


def test_recipe_scene_with_a_height_map_steps() -> None:
    env = make_env(sets=["scene=path_boxes", "scene.count=3"], observers="height_map")
    obs = env.reset()
    assert env.scene.name == "path_boxes" and len(env.scene.mocap_bodies()) == 3
    for _ in range(3):
        obs, reward, *_ = env.step(torch.zeros(4, env.action_dim))
    assert torch.isfinite(obs["actor"]).all() and torch.isfinite(reward).all()
