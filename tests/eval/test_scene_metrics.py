"""Scene metrics: penetration depth from MuJoCo contacts, agreement with scene contact labels,
and both in ``evaluate``'s report and the ``retarget eval`` table."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import torch

from retarget.cli.eval_cmd import table
from retarget.env import EnvOptions, RetargetEnv
from retarget.eval import EvalSettings, evaluate
from retarget.eval.metrics import MetricProbe
from retarget.motion.procedural import default_motions
from retarget.plugins.characters.human import Human
from retarget.plugins.scenes.motion_props import MotionProps
from retarget.testing import fake_context

IDLE, SIT = default_motions(names=("idle", "sit_stand"))
STILL = {"position": 0.0, "yaw": 0.0}


def _box_env(num_envs: int = 2) -> RetargetEnv:
    """A 40 cm box of 60 x 60 cm centred at (1, 0), nothing else but the floor."""
    box = {"kind": "box", "position": [1.0, 0.0], "height": 0.4, "size": [0.6, 0.6]}
    scene = MotionProps(MotionProps.Config(clips={"idle": [box]}, randomize=STILL))
    return RetargetEnv(Human(), [IDLE], scene=scene, options=EnvOptions(num_envs=num_envs))


def test_penetration_is_the_overlap_into_scene_geoms() -> None:
    env = _box_env()
    qpos = np.repeat(env.reference.qpos64[:1], 2, axis=0)
    feet_z = env.reference.arrays["body_pos"][0, :, 2].min().item()
    # env 0 stands on the box sunk 5 cm into its top, env 1 on the floor 2 m away
    qpos[0, :2] = (1.0, 0.0)
    qpos[0, 2] += 0.4 - 0.05
    qpos[1, :2] = (-2.0, 0.0)
    env.sim.reset(np.arange(2), qpos, np.zeros((2, env.layout.nv)))
    deepest, mean = env.sim.penetration()
    floor_overlap = deepest[1]  # the kinematic pose's own few millimetres into the floor
    assert 0.0 <= floor_overlap < 0.01 and feet_z < 0.2
    assert deepest[0] == pytest.approx(0.05 + floor_overlap, abs=0.005)
    assert 0.0 < mean[0] <= deepest[0]
    env.sim.reset(
        np.arange(2),
        qpos + np.array([0, 0, 1.0] + [0] * (qpos.shape[1] - 3)),
        np.zeros((2, env.layout.nv)),
    )
    deepest, mean = env.sim.penetration()  # 1 m up in the air: nothing touches
    assert (deepest == 0).all() and (mean == 0).all()


def test_scene_contact_agreement_by_hand() -> None:
    layout = _box_env(1).layout
    ctx = fake_context(layout, 2, seed=0)
    names, groups = list(layout.body_names), list(layout.body_groups)
    up = torch.zeros(2, layout.num_bodies)
    up[:, names.index("l_foot")] = 300.0
    up[:, names.index("r_foot")] = 300.0
    up[1, names.index("pelvis")] = 40.0  # under 50 N: not a contact
    labels = torch.zeros(2, len(groups), dtype=torch.bool)
    for g in ("left_foot", "right_foot", "pelvis"):
        labels[:, groups.index(g)] = True
    ctx = replace(
        ctx,
        sim=replace(ctx.sim, contact_force_up=up),
        ref=replace(ctx.ref, scene_contacts=labels),
    )
    pen = (torch.tensor([0.02, 0.0]), torch.tensor([0.01, 0.0]))
    m = MetricProbe(layout)(ctx, pen)
    # 6 links (feet, hands, pelvis, spine): env 0 misses the pelvis (1 of 6 wrong), env 1 too
    assert torch.allclose(m.scene_contact_agree, torch.tensor([5 / 6, 5 / 6]))
    assert m.penetration_max is pen[0] and m.penetration_mean is pen[1]


def test_eval_report_and_table_carry_the_scene_metrics() -> None:
    scene = MotionProps(MotionProps.Config(randomize=STILL))
    env = RetargetEnv(Human(), [SIT], scene=scene, options=EnvOptions(num_envs=4))
    report = evaluate(
        env,
        lambda obs: torch.zeros(4, env.action_dim),
        EvalSettings(every=60, max_seconds=1.0),
    )
    overall = report["overall"]
    for key in ("scene_contact_agreement", "penetration_mean_mm", "penetration_max_mm"):
        assert np.isfinite(overall[key]), key
    assert 0.0 <= overall["scene_contact_agreement"] <= 1.0
    assert 0.0 <= overall["penetration_mean_mm"] <= overall["penetration_max_mm"]
    assert overall["penetration_max_mm"] > 0  # feet and seat are touched, MuJoCo overlaps a bit
    header = [c.header for c in table(report).columns]
    assert {"scene\ncont", "pen\nmax mm"} <= set(header)
