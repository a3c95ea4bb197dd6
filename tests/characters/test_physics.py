"""Real MuJoCo physics of the characters: dropped with zero torque, and passive secondary motion."""

from __future__ import annotations

import sys
from pathlib import Path

import mujoco
import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from _characters_common import CHARACTERS, floor_world

from retarget.plugins.characters.dino import Dino
from retarget.plugins.characters.oppy import Oppy


@pytest.mark.parametrize("cls", CHARACTERS, ids=lambda c: c.name)
def test_dropped_with_zero_torque_stays_finite_for_10s(cls) -> None:
    c = cls()
    m = floor_world(c.build_spec())
    d = mujoco.MjData(m)
    d.qpos[2] += 0.3
    lowest = np.inf
    for _ in range(round(10.0 / m.opt.timestep)):
        mujoco.mj_step(m, d)
        lowest = min(lowest, d.qpos[2])
    assert np.isfinite(d.qpos).all() and np.isfinite(d.qvel).all()
    assert d.warning[mujoco.mjtWarning.mjWARN_BADQACC].number == 0
    assert lowest > 0.0, "the root went below the floor"
    assert np.abs(d.qvel).max() < 5.0, "a limp body should have come (nearly) to rest in 10 s"
    print(f"\n{c.name}: after 10 s root z {d.qpos[2]:.3f} m, |qvel| max {np.abs(d.qvel).max():.3f}")


def _shaker(c) -> mujoco.MjModel:
    """The character with active joints welded and the free root replaced by a sideways slide.

    A stiff servo drives the slide (a person swaying); the root cannot fall, so any passive
    motion comes from the sway alone (at rest the springs balance gravity, see test_bodies).
    """
    spec = c.build_spec()
    passive = set(c.passive_joints())
    for j in list(spec.joints):
        if j.name not in passive:
            for act in [a for a in spec.actuators if a.target == j.name]:
                spec.delete(act)
            spec.delete(j)
    root = spec.worldbody.first_body()
    root.add_joint(name="shake", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 1, 0])
    mass = c.built().mass
    w = 2 * np.pi * 15.0  # a stiff 15 Hz position servo on the slide, critically damped
    servo = spec.add_actuator(name="shake", target="shake", trntype=mujoco.mjtTrn.mjTRN_JOINT)
    servo.set_to_position(kp=mass * w * w, kv=2 * mass * w)
    return spec.compile()


def _swing(c, joints: list[str], seconds: float = 3.0) -> tuple[float, float]:
    """Sway the body sideways for 0.4 s (+/- 0.1 m at 2.5 Hz), then hold it still.

    Returns the largest excursion (deg) of ``joints`` in the second after the shake and in the
    last 0.5 s.
    """
    m = _shaker(c)
    d = mujoco.MjData(m)
    ids = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, j) for j in joints]
    qadr = m.jnt_qposadr[ids]
    dt = m.opt.timestep
    w = 2 * np.pi * 2.5
    after, late = 0.0, 0.0
    for i in range(round(seconds / dt)):
        t = i * dt
        d.ctrl[0] = 0.1 * np.sin(w * t) if t < 0.4 else 0.0
        mujoco.mj_step(m, d)
        exc = np.degrees(np.abs(d.qpos[qadr])).max()
        if 0.4 <= t < 1.4:
            after = max(after, exc)
        if t >= seconds - 0.5:
            late = max(late, exc)
    assert np.isfinite(d.qpos).all()
    return after, late


def test_oppy_ears_swing_after_a_push() -> None:
    c = Oppy()
    ears = [j for j in c.passive_joints() if "_ear" in j]
    after, late = _swing(c, ears)
    print(f"\noppy ears: {after:.1f} deg swing in the second after the push, {late:.2f} deg "
          "in the last 0.5 s")
    assert after > 3.0, "the ears should visibly swing"
    assert late < 0.5 * after, "the ears' swing should decay (damped springs)"


def test_dino_passive_tail_swings_after_a_push() -> None:
    c = Dino()
    tail = [j for j in c.passive_joints() if j.startswith("tail")]
    assert len(tail) == 12
    after, late = _swing(c, tail, seconds=4.0)
    print(f"\ndino passive tail: {after:.1f} deg swing after the push, {late:.2f} deg in the "
          "last 0.5 s")
    assert after > 2.0
    assert late < 0.5 * after
