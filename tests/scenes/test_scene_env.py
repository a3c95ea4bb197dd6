"""Scenes inside RetargetEnv: recipes, per-env props in the shared model, scene DoFs."""

from __future__ import annotations

import numpy as np
import torch

from retarget.env import RetargetEnv
from retarget.env.build import env_from_recipe
from retarget.env.observations import proprio_size
from retarget.motion.procedural import default_motions
from retarget.recipe import load
from retarget.registry.loader import load_plugins

REGISTRY = load_plugins(strict=True)
CLIPS = default_motions()[:2]


def make_env(path=None, num_envs: int = 4, sets=(), **shorthands: str) -> RetargetEnv:
    resolved = load(
        path, REGISTRY, shorthands={"character": "human", **shorthands}, assignments=list(sets)
    )
    return env_from_recipe(resolved, num_envs=num_envs, threads=1, clips=CLIPS)


def test_recipe_scene_and_height_map() -> None:
    env = make_env(sets=["scene=chair"], observers="height_map")
    assert env.scene.name == "chair" and [o.name for o in env.observers] == ["height_map"]
    obs = env.reset()
    assert env.observation_size("height_map") == 120
    assert obs["actor"].shape == (4, env.obs_dims["actor"])
    obs, reward, *_ = env.step(torch.zeros(4, env.action_dim))
    assert torch.isfinite(obs["actor"]).all() and torch.isfinite(reward).all()


def test_recipe_file_with_a_boxes_table(tmp_path) -> None:
    recipe = tmp_path / "boxes.yaml"
    recipe.write_text(
        "scene:\n  type: boxes\n  preset: stepping_path\n"
        "  randomize: {position: 0.05, yaw: 0.05}\n"
        "observers: [height_map, point_cloud]\n"
    )
    env = make_env(recipe, num_envs=3)
    assert env.scene.config.preset == "stepping_path" and env.scene.randomization.position == 0.05
    env.reset()
    mocap = env.sim.raw("mocap_pos")
    assert mocap.shape == (3, 4, 3)
    # the model's props sit where the scene says each env's props are, and differ per env
    assert np.allclose(mocap, env.scene.placement()[..., :3].numpy())
    assert not np.allclose(mocap[0], mocap[1])
    off = env.scene.placement()[..., :2] - env.scene._tables.base[:, :2]
    assert (off.norm(dim=-1) <= 0.05 + 1e-9).all() and (off.norm(dim=-1) > 0).all()
    obs, *_ = env.step(torch.zeros(3, env.action_dim))
    assert torch.isfinite(obs["actor"]).all()


def test_rotating_chair_env_keeps_scene_dofs_out_of_the_character() -> None:
    env = make_env(sets=["scene=rotating_chair"], num_envs=4)
    model, layout = env.world.model, env.layout
    assert model.nq == layout.nq + 1 and model.nv == layout.nv + 1
    assert env.sim.state.qpos.shape == (4, layout.nq)
    assert env.reference.qpos.shape[1] == layout.nq
    assert env.observation_size("proprio") == proprio_size(layout)
    env.reset()
    zeros = torch.zeros(4, env.action_dim)
    for _ in range(5):
        obs, reward, *_ = env.step(zeros)
        assert torch.isfinite(reward).all() and torch.isfinite(obs["critic"]).all()
    # turn every chair, then reset two envs: their chairs come back, the others keep turning
    qpos, qvel = env.sim.raw("qpos"), env.sim.raw("qvel")
    qpos[:, -1], qvel[:, -1] = 0.7, 1.0
    character = qpos[:, : layout.nq].copy()
    env._reset_envs(torch.tensor([1, 3]))
    assert np.allclose(qpos[[1, 3], -1], 0.0) and np.allclose(qvel[[1, 3], -1], 0.0)
    assert np.allclose(qpos[[0, 2], -1], 0.7) and np.allclose(
        qpos[[0, 2], : layout.nq], character[[0, 2]]
    )
    # the reset envs start at their reference pose (character block only)
    assert not np.allclose(qpos[[1, 3], : layout.nq], character[[1, 3]])
    env.step(zeros)
    assert np.isfinite(env.sim.raw("qpos")).all()


def test_scene_env_state_dict_round_trip() -> None:
    env = make_env(sets=["scene=boxes"], num_envs=3, observers="height_map")
    env.reset()
    zeros = torch.zeros(3, env.action_dim)
    env.step(zeros)
    state = env.state_dict()
    a = env.step(zeros)[0]["actor"]
    other = make_env(sets=["scene=boxes", "seed=5"], num_envs=3, observers="height_map")
    other.reset()
    other.load_state_dict(state)
    b = other.step(zeros)[0]["actor"]
    assert torch.equal(a, b)
