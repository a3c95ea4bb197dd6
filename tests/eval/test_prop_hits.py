"""Feet hitting props: a foot on a box top, against a box side, in the air; in the eval report."""

from __future__ import annotations

import numpy as np
import torch

from retarget.cli.eval_cmd import table
from retarget.env import EnvOptions, RetargetEnv
from retarget.eval import EvalSettings, evaluate
from retarget.eval.prop_hits import foot_geoms, foot_prop_hits, prop_geoms
from retarget.motion.procedural import default_motions
from retarget.plugins.characters.human import Human
from retarget.plugins.scenes.flat import Flat
from retarget.plugins.scenes.motion_props import MotionProps
from retarget.plugins.scenes.path_boxes import PathBoxes

IDLE, WALK = default_motions(names=("idle", "walk"))
BOX_X, HALF, TOP = 1.0, 0.3, 0.4  # a 40 cm box of 60 x 60 cm centred at (1, 0)


def _box_env(num_envs: int = 3) -> RetargetEnv:
    box = {"kind": "box", "position": [BOX_X, 0.0], "height": TOP, "size": [2 * HALF] * 2}
    still = {"position": 0.0, "yaw": 0.0}
    scene = MotionProps(MotionProps.Config(clips={"idle": [box]}, randomize=still))
    return RetargetEnv(Human(), [IDLE], scene=scene, options=EnvOptions(num_envs=num_envs))


def _front_of_feet(env: RetargetEnv) -> float:
    """Largest world x of any foot box geom in env 0 (foot geoms are boxes: exact extent)."""
    model = env.world.model
    feet = np.nonzero(foot_geoms(model, env.layout))[0]
    assert (model.geom_type[feet] == 6).all()
    xpos = env.sim.raw("geom_xpos")[0, feet]
    xmat = env.sim.raw("geom_xmat")[0, feet].reshape(-1, 3, 3)
    reach = np.abs(xmat[:, 0, :]) @ np.eye(3) * model.geom_size[feet]
    return float((xpos[:, 0] + reach.sum(-1)).max())


def test_top_side_and_air_by_hand() -> None:
    env = _box_env()
    model = env.world.model
    feet, props = foot_geoms(model, env.layout), prop_geoms(model)
    assert props.sum() == 1 and feet.sum() == 4  # the box; feet and toes
    qpos = np.repeat(env.reference.qpos64[:1], 3, axis=0)
    qpos[:, :2] = (-2.0, 0.0)
    env.sim.reset(np.arange(3), qpos, np.zeros((3, env.layout.nv)))
    front = _front_of_feet(env) - (-2.0)  # how far the feet reach ahead of the root
    # env 0 stands on the box top sunk 1 cm; env 1 on the floor with its toes 2 cm into the
    # box's side; env 2 1 m up in the air next to the box
    qpos[0, :2], qpos[0, 2] = (BOX_X, 0.0), qpos[0, 2] + TOP - 0.01
    qpos[1, :2] = (BOX_X - HALF - front + 0.02, 0.0)
    qpos[2, :2], qpos[2, 2] = (BOX_X - HALF - front + 0.02, 0.0), qpos[2, 2] + 1.0
    env.sim.reset(np.arange(3), qpos, np.zeros((3, env.layout.nv)))
    hits = env.sim.each_env(lambda d: foot_prop_hits(model, d, feet, props))
    assert hits == [(True, False), (False, True), (False, False)]
    # a force threshold above what the pressed toes push with counts nothing
    strong = env.sim.each_env(lambda d: foot_prop_hits(model, d, feet, props, newtons=1e6))
    assert strong == [(False, False)] * 3


def test_report_counts_box_hits_only_with_props() -> None:
    settings = EvalSettings(every=60, max_seconds=1.0)
    scene = PathBoxes(PathBoxes.Config(count=6, clear=0.0, lateral=0.0, ahead=False))
    env = RetargetEnv(Human(), [WALK], scene=scene, options=EnvOptions(num_envs=4))
    report = evaluate(env, lambda obs: torch.zeros(4, env.action_dim), settings)
    overall = report["overall"]
    for side in ("top", "side"):
        assert 0.0 <= overall[f"box_{side}_fraction"] <= 1.0
        assert overall[f"box_{side}_per_min"] >= 0.0
    # six boxes anywhere on the path, clear of nothing: some runs start on or against one
    assert overall["box_top_fraction"] + overall["box_side_fraction"] > 0
    assert "box\nside/m" in [c.header for c in table(report).columns]
    flat = RetargetEnv(Human(), [WALK], scene=Flat(), options=EnvOptions(num_envs=4))
    plain = evaluate(flat, lambda obs: torch.zeros(4, flat.action_dim), settings)["overall"]
    assert not any(k.startswith("box_") for k in plain)
