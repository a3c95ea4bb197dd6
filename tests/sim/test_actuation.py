"""Torque vs PD actuation: the servo law, the torque limits, and conversions in both directions."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from retarget.plugins.characters.human import Human
from retarget.sim import apply_actuation
from retarget.sim.world import build_world


def _human_model() -> mujoco.MjModel:
    return build_world(Human(), None).model


ARRAYS = ("actuator_gear", "actuator_gainprm", "actuator_biasprm", "actuator_biastype",
          "actuator_ctrlrange")  # fmt: skip


def test_pd_servo_follows_its_law_and_stays_within_torque_limits() -> None:
    model = _human_model()
    limit = model.actuator_forcerange[:, 1].copy()
    apply_actuation(model, "pd", saturation=0.5, damping=0.1)
    data = mujoco.MjData(model)
    rng = np.random.default_rng(0)
    joints = model.actuator_trnid[:, 0]
    qadr, dadr = model.jnt_qposadr[joints], model.jnt_dofadr[joints]
    data.qpos[qadr] = rng.uniform(-0.3, 0.3, model.nu)
    data.qvel[dadr] = rng.uniform(-2.0, 2.0, model.nu)
    data.ctrl[:] = rng.uniform(-1.0, 1.0, model.nu)
    mujoco.mj_forward(model, data)
    lower, upper = model.jnt_range[joints].T
    scale = np.maximum(np.abs(lower), np.abs(upper))
    target = np.clip(data.ctrl * scale, lower, upper)  # MuJoCo clamps ctrl to the joint range
    kp = limit / 0.5
    expected = np.clip(kp * (target - data.qpos[qadr]) - 0.1 * kp * data.qvel[dadr], -limit, limit)
    np.testing.assert_allclose(data.actuator_force, expected, rtol=1e-9, atol=1e-9)
    assert (np.abs(data.actuator_force) <= limit + 1e-9).all()
    assert (np.abs(data.actuator_force) >= limit - 1e-9).any()  # some saturate: limits matter


def test_zero_action_holds_the_t_pose_angle() -> None:
    model = _human_model()
    apply_actuation(model, "pd")
    data = mujoco.MjData(model)
    data.qpos[2] += 5.0  # far above the floor: only the servos act on the joints
    joints = model.actuator_trnid[:, 0]
    qadr = model.jnt_qposadr[joints]
    data.qpos[qadr] = 0.2
    model.opt.gravity[:] = 0.0
    for _ in range(720):  # two seconds
        mujoco.mj_step(model, data)
    assert np.abs(data.qpos[qadr]).max() < 0.02


def test_conversions_are_idempotent_and_reversible() -> None:
    model = _human_model()
    original = {k: getattr(model, k).copy() for k in ARRAYS}
    apply_actuation(model, "pd", saturation=0.3)
    once = {k: getattr(model, k).copy() for k in ARRAYS}
    apply_actuation(model, "pd", saturation=0.3)
    for k in ARRAYS:
        np.testing.assert_array_equal(getattr(model, k), once[k], err_msg=k)
    apply_actuation(model, "torque")
    for k in ARRAYS:
        np.testing.assert_array_equal(getattr(model, k), original[k], err_msg=k)


def test_bad_settings_are_refused() -> None:
    model = _human_model()
    with pytest.raises(ValueError, match="unknown actuation 'servo'"):
        apply_actuation(model, "servo")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="saturation"):
        apply_actuation(model, "pd", saturation=0.0)
