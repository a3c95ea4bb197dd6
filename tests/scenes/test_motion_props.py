"""``motion_props``: props from the motion (fitted seat and boxes), sidecars, recipe fields."""

from __future__ import annotations

from dataclasses import replace

import mujoco
import numpy as np
import pytest
import torch

from retarget import PluginError
from retarget.env import EnvOptions, RetargetEnv
from retarget.motion.procedural import default_motions
from retarget.motion.scene_fit import fit_boxes, fit_seats
from retarget.plugins.characters.human import Human
from retarget.plugins.scenes.motion_props import MotionProps
from retarget.testing import parametrize_with_checks

SIT, IDLE = default_motions(names=("sit_stand", "idle"))
STILL = {"position": 0.0, "yaw": 0.0}


@parametrize_with_checks([MotionProps])
def test_motion_props_contract(plugin, check) -> None:
    check(plugin)


def test_fitted_seat_lands_under_the_sitting_pelvis() -> None:
    pelvis = SIT.global_pos[:, 0]
    seated = pelvis[:, 2] < pelvis[:, 2].min() + 0.005
    (seat,) = fit_seats(SIT)
    assert seat.kind == "seat"
    # the generator seats the pelvis over a 45 cm seat (scaled by the subject's height)
    expected = 0.45 * SIT.height / 1.75
    assert seat.height == pytest.approx(expected, abs=0.03)
    assert np.hypot(*(np.array(seat.position) - pelvis[seated, :2].mean(0))) < 0.03
    assert fit_seats(IDLE) == [] and fit_boxes(SIT) == [] and fit_boxes(IDLE) == []


def test_seat_in_the_env_carries_the_reference_pelvis() -> None:
    """Built into the world: the seat's height map is the seat height under the pelvis, and
    the kinematic reference's pelvis touches it (contact labels) only while seated, sinking
    at most 2 cm into it (MuJoCo contact distances)."""
    scene = MotionProps(MotionProps.Config(randomize=STILL))
    env = RetargetEnv(Human(), [SIT], scene=scene, options=EnvOptions(num_envs=2))
    (seat,) = scene.fitted
    pelvis_xy = torch.tensor(seat.position).reshape(1, 1, 2).expand(2, 1, 2)
    assert torch.allclose(scene.height_at(pelvis_xy), torch.tensor(seat.height).float())
    ref, layout = env.reference, env.layout
    pelvis = layout.body_names.index("pelvis")
    z = ref.arrays["body_pos"][:, pelvis, 2]
    labels = ref.scene_contacts[:, list(layout.body_groups).index("pelvis")]
    assert labels[z < z.min() + 0.01].all() and not labels[z > z.max() - 0.01].any()
    m, d = env.world.model, mujoco.MjData(env.world.model)
    seat_body = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, scene.mocap_bodies()[0])
    deepest = 0.0
    for f in range(0, ref.num_frames, 5):
        d.qpos[: layout.nq] = ref.qpos64[f]
        mujoco.mj_forward(m, d)
        for c in d.contact[: d.ncon]:
            bodies = {int(m.geom_bodyid[c.geom1]), int(m.geom_bodyid[c.geom2])}
            if bodies == {seat_body, layout.body_ids[pelvis]}:
                deepest = min(deepest, c.dist)
    assert -0.02 < deepest < 0.0


def test_boxes_under_feet_resting_above_the_floor() -> None:
    """Idle on a 20 cm platform for the middle 3 s: one box under both feet, 20 cm high."""
    root = IDLE.root_pos.copy()
    t = np.arange(IDLE.num_frames) / IDLE.fps
    up = (t > 1.5) & (t < 4.5)
    root[up, 2] += 0.2
    raised = replace(IDLE, root_pos=root, _fk=None)
    (step,) = fit_boxes(raised)
    feet = raised.global_pos[up][:, [3, 7], :2].reshape(-1, 2).mean(0)
    assert step.kind == "box" and step.height == pytest.approx(0.2, abs=0.03)
    assert np.hypot(*(np.array(step.position) - feet)) < 0.1
    assert fit_seats(raised) == []


def test_sidecar_and_recipe_field_win_over_fitting(tmp_path) -> None:
    clip = replace(SIT, source=tmp_path / "sit.bvh")
    (tmp_path / "sit.scene.yaml").write_text(
        "props:\n  - {kind: seat, position: [1.0, 2.0], height: 0.5}\n"
    )
    scene = MotionProps()
    scene.fit_motion([clip])
    assert [(s.position, s.height) for s in scene.fitted] == [((1.0, 2.0), 0.5)]
    given = {"sit_stand": [{"kind": "box", "position": [0, 0], "height": 0.3}]}
    scene = MotionProps(MotionProps.Config(clips=given))
    scene.fit_motion([clip])
    assert [(s.kind, s.height) for s in scene.fitted] == [("box", 0.3)]
    off = MotionProps(MotionProps.Config(auto=False, sidecar=False))
    off.fit_motion([clip])
    assert off.fitted == []
    (tmp_path / "sit.scene.yaml").write_text("props:\n  - {kind: seat, position: [1.0, 2.0]}\n")
    with pytest.raises(PluginError, match=r"sit\.scene\.yaml.*props\.0\.height|height"):
        MotionProps().fit_motion([clip])


def test_recipe_with_motion_props_and_the_contact_reward(tmp_path) -> None:
    """A recipe names the scene and the reward; the sitting clip gets its fitted seat, and a
    step's contact reward is computed against its labels."""
    from retarget.env.build import env_from_recipe
    from retarget.recipe import load
    from retarget.registry.loader import load_plugins

    recipe = tmp_path / "sit.yaml"
    recipe.write_text(
        "character: human\n"
        "scene: {type: motion_props, randomize: {position: 0.05, yaw: 0.05}}\n"
        "rewards:\n  contact: {weight: 1.0, k: 1.0}\n"
    )
    resolved = load(recipe, load_plugins(strict=True))
    env = env_from_recipe(resolved, num_envs=2, threads=1, clips=[SIT])
    assert [s.kind for s in env.scene.fitted] == ["seat"]
    env.reset()
    _, reward, *_ = env.step(torch.zeros(2, env.action_dim))
    assert torch.isfinite(reward).all()
    assert "contact" in env.rewards.terms
