"""Foot clearance over props: a sphere "foot" above, on and beside a mocap box."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from retarget.eval.prop_clearance import foot_clearance
from retarget.eval.prop_hits import prop_geoms

XML = """
<mujoco>
  <worldbody>
    <geom name="floor" type="plane" size="5 5 0.1"/>
    <body name="box" mocap="true" pos="0 0 0.1">
      <geom name="box" type="box" size="0.3 0.15 0.1"/>
    </body>
    <body name="foot" pos="0 0 1">
      <freejoint/>
      <geom name="foot" type="sphere" size="0.05"/>
    </body>
  </worldbody>
</mujoco>
"""


@pytest.mark.parametrize(
    ("xyz", "expected"),
    [
        ((0.0, 0.0, 0.5), 0.25),  # 0.45 lowest point above a 0.2 top
        ((0.25, 0.1, 0.22), -0.03),  # inside the footprint, sunk 3 cm into the top
        ((0.0, 0.2, 0.3), math.inf),  # beside the box (half width 0.15)
        ((0.4, 0.0, 0.3), math.inf),  # beyond its end (half length 0.3)
    ],
)
def test_clearance_above_the_footprint_only(xyz: tuple, expected: float) -> None:
    model = mujoco.MjModel.from_xml_string(XML)
    data = mujoco.MjData(model)
    data.qpos[:3] = xyz
    mujoco.mj_kinematics(model, data)
    feet = np.array([model.geom(i).name == "foot" for i in range(model.ngeom)])
    props = prop_geoms(model)
    assert props.sum() == 1 and not props[0], "only the mocap box is a prop"
    (clearance,) = foot_clearance(model, data, feet, props)
    assert clearance == pytest.approx(expected, abs=1e-9)


def test_a_turned_box_has_a_turned_footprint() -> None:
    model = mujoco.MjModel.from_xml_string(XML)
    data = mujoco.MjData(model)
    half = math.radians(90) / 2
    data.mocap_quat[0] = [math.cos(half), 0, 0, math.sin(half)]  # long side now along y
    data.qpos[:3] = (0.0, 0.25, 0.5)
    mujoco.mj_kinematics(model, data)
    feet = np.array([model.geom(i).name == "foot" for i in range(model.ngeom)])
    (clearance,) = foot_clearance(model, data, feet, prop_geoms(model))
    assert clearance == pytest.approx(0.25, abs=1e-9)
