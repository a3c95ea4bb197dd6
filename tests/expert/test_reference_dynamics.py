"""The reference-dynamics check: a centre of mass that falls faster than gravity drops the
distance free fall would not, one that falls at gravity drops none, scene props do not count,
and a person's run retargeted to the larger Dino asks for more of it than on the human."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest
from helpers import SHARED_MOCAP

from retarget.expert.reference_dynamics import (
    com_heights,
    drop_beyond_fall,
    drop_beyond_fall_per_second,
)

BODY_AND_PROP = """
<mujoco>
  <worldbody>
    <body name="character" pos="0 0 1">
      <freejoint/>
      <geom type="sphere" size="0.1" mass="70"/>
      <body name="arm" pos="0 0 0.5"><geom type="sphere" size="0.05" mass="10"/></body>
    </body>
    <body name="prop" pos="3 0 5"><joint type="slide" axis="0 0 1"/>
      <geom type="box" size="0.5 0.5 0.5" mass="500"/></body>
  </worldbody>
</mujoco>
"""


def _falling(model: mujoco.MjModel, g_multiple: float, frames: int = 40, fps: float = 30.0):
    t = np.arange(frames) / fps
    qpos = np.tile(model.qpos0[:7], (frames, 1))
    qpos[:, 2] = 10.0 - 0.5 * g_multiple * 9.81 * t**2
    return qpos


def test_falling_at_gravity_is_possible_and_faster_is_not() -> None:
    model = mujoco.MjModel.from_xml_string(BODY_AND_PROP)
    qpos = _falling(model, 1.0)
    heights = com_heights(model, qpos)
    # the character's own centre of mass (body + arm), never the 500 kg prop's
    assert heights[0] == pytest.approx(10.0 + 0.5 * 10 / 80, abs=1e-9)
    assert drop_beyond_fall_per_second(model, qpos, 30.0) == pytest.approx(0.0, abs=1e-9)
    # half a g too much for the whole clip: 0.5 * (g / 2) * t^2 over its 38 second differences
    t = 38 / 30.0
    expected = 0.5 * (0.5 * 9.81) * t**2 / (39 / 30.0)
    fast = drop_beyond_fall_per_second(model, _falling(model, 1.5), 30.0)
    assert fast == pytest.approx(expected, rel=0.05)
    # a landing ends the stretch: what follows (held still) adds nothing
    z = 10.0 - 0.5 * 1.5 * 9.81 * (np.arange(40) / 30.0) ** 2
    landed = np.concatenate([z[:20], np.full(20, z[19])])
    assert drop_beyond_fall(landed, 30.0) == pytest.approx(drop_beyond_fall(z[:20], 30.0))
    assert 0.0 < drop_beyond_fall(z[:20], 30.0) < drop_beyond_fall(z, 30.0)
    assert drop_beyond_fall_per_second(model, qpos[:1], 30.0) == 0.0
    with pytest.raises(ValueError, match="qpos must be"):
        com_heights(model, np.zeros((3, model.nq + 1)))


NO_MOCAP = "shared mocap clips not found (set RETARGET_SHARED_DATA)"


@pytest.mark.skipif(not (SHARED_MOCAP / "bandai_d2_run_normal_040.bvh").is_file(), reason=NO_MOCAP)
def test_a_run_retargeted_to_the_dino_asks_its_body_to_fall_faster_than_the_humans() -> None:
    from retarget import load_plugins
    from retarget.env.build import env_from_recipe
    from retarget.recipe import load

    registry = load_plugins(strict=False)
    drop = {}
    for kind in ("run_normal_040", "walk_normal_020"):
        for character in ("human", "dino"):
            clip = SHARED_MOCAP / f"bandai_d2_{kind}.bvh"
            recipe = load(None, registry, shorthands={"character": character, "scene": None,
                                                      "motions": str(clip)})  # fmt: skip
            env = env_from_recipe(recipe, registry=registry, num_envs=1, threads=1)
            fps = 1.0 / env.sim.settings.control_dt
            drop[kind, character] = drop_beyond_fall_per_second(
                env.sim.model, env.reference.qpos64, fps)
    assert drop["walk_normal_020", "human"] == drop["walk_normal_020", "dino"] == 0.0
    assert drop["run_normal_040", "dino"] > 1.5 * drop["run_normal_040", "human"] > 0.0
