"""Velocity-space moves of MuJoCo positions over many rows agree with MuJoCo's own."""

from __future__ import annotations

import mujoco
import numpy as np

from retarget.registry.loader import load_plugins
from retarget.sim.tangent import Tangent


def _model_with_a_ball() -> mujoco.MjModel:
    """The human (free root, hinges) plus a prop on a ball joint."""
    spec = load_plugins().get("character", "human").cls().build_spec()
    prop = spec.worldbody.add_body(name="prop", pos=[2, 0, 1])
    prop.add_joint(name="prop_ball", type=mujoco.mjtJoint.mjJNT_BALL)
    prop.add_geom(size=[0.1, 0, 0])
    return spec.compile()


def test_integrate_and_difference_match_mujoco() -> None:
    model = _model_with_a_ball()
    rng = np.random.default_rng(0)
    tangent = Tangent(model)
    rows = 6
    qpos = np.repeat(model.qpos0[None], rows, axis=0)
    qpos = tangent.integrate(qpos, rng.normal(0, 0.5, (rows, model.nv)))  # varied start poses
    dq = rng.normal(0, 0.3, (rows, model.nv))
    mine = tangent.integrate(qpos, dq)
    back = tangent.difference(mine, qpos)
    for i in range(rows):
        theirs = qpos[i].copy()
        mujoco.mj_integratePos(model, theirs, dq[i], 1.0)
        assert np.allclose(mine[i], theirs, atol=1e-10)
        diff = np.zeros(model.nv)
        mujoco.mj_differentiatePos(model, diff, 1.0, qpos[i], mine[i])
        assert np.allclose(back[i], diff, atol=1e-9)
    assert np.allclose(back, dq, atol=1e-9)  # a round trip returns the step
    assert np.allclose(tangent.difference(qpos, qpos[:1])[0], 0.0)  # one base row broadcasts
