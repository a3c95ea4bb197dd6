"""How a policy's action in ``[-1, 1]`` becomes joint torque: direct torque or PD targets.

``torque`` (the paper's choice, Sec. 3.6) is how characters are built: every actuated hinge has
a ``motor`` whose gear is the joint's torque limit. ``pd`` rewrites those actuators in the
compiled model into proportional-derivative servos, still clamped to the same torque limits
(App. D), so both modes respect the character's strength:

    torque = clamp(kp * (target - q) - kd * qdot, -limit, limit)
    target = action * scale,   scale = max(|lower|, |upper|) of the joint's range

Action 0 is the zero (T-pose) angle of every joint, so an untrained policy holds the character
upright instead of letting it collapse, and the control range is cut to the joint's limits so
that every reachable target is a legal angle. ``kp = limit / saturation`` (the error in radians
at which the servo reaches its torque limit) and ``kd = damping * kp`` (``damping`` in seconds:
the servo's time constant). The paper reports torques working better than PD targets with
billions of samples on a GPU; with the few million an hour a CPU gives, PD targets make the
first steps of learning (standing) free, which is why the option exists. The conversion is
computed from the model's own joint ranges and force limits, so applying it twice is harmless.
"""

from __future__ import annotations

import mujoco
import numpy as np

from retarget.settings.sim import ACTUATIONS, Actuation


def apply_actuation(
    model: mujoco.MjModel,
    mode: Actuation,
    *,
    saturation: float = 0.5,
    damping: float = 0.1,
) -> None:
    """Make ``model``'s joint actuators act as ``mode`` (see module doc); in place.

    Only actuators that drive one hinge with a force limit are converted (the ones
    :mod:`retarget.character.builder` creates); other actuators are left alone.
    """
    if mode not in ACTUATIONS:
        raise ValueError(f"unknown actuation {mode!r}; choose one of {', '.join(ACTUATIONS)}")
    if saturation <= 0 or damping < 0:
        raise ValueError("pd saturation must be > 0 and damping >= 0")
    ids = _joint_actuators(model)
    if ids.size == 0:
        return
    limit = model.actuator_forcerange[ids, 1].copy()
    if mode == "torque":
        model.actuator_gaintype[ids] = mujoco.mjtGain.mjGAIN_FIXED
        model.actuator_biastype[ids] = mujoco.mjtBias.mjBIAS_NONE
        model.actuator_gainprm[ids] = 0.0
        model.actuator_gainprm[ids, 0] = 1.0
        model.actuator_biasprm[ids] = 0.0
        model.actuator_gear[ids, 0] = limit
        model.actuator_ctrlrange[ids] = (-1.0, 1.0)
        return
    joints = model.actuator_trnid[ids, 0]
    lower, upper = model.jnt_range[joints, 0], model.jnt_range[joints, 1]
    scale = np.maximum(np.maximum(np.abs(lower), np.abs(upper)), 1e-6)
    kp = limit / saturation
    kd = damping * kp
    model.actuator_gear[ids, 0] = 1.0
    model.actuator_gaintype[ids] = mujoco.mjtGain.mjGAIN_FIXED
    model.actuator_biastype[ids] = mujoco.mjtBias.mjBIAS_AFFINE
    model.actuator_gainprm[ids] = 0.0
    model.actuator_gainprm[ids, 0] = kp * scale  # force = kp*scale*ctrl - kp*q - kd*qdot
    model.actuator_biasprm[ids] = 0.0
    model.actuator_biasprm[ids, 1] = -kp
    model.actuator_biasprm[ids, 2] = -kd
    model.actuator_ctrlrange[ids, 0] = np.clip(lower / scale, -1.0, 1.0)
    model.actuator_ctrlrange[ids, 1] = np.clip(upper / scale, -1.0, 1.0)


def _joint_actuators(model: mujoco.MjModel) -> np.ndarray:
    """Indices of force-limited actuators that drive a single hinge."""
    hinge = mujoco.mjtJoint.mjJNT_HINGE
    return np.asarray(
        [
            i
            for i in range(model.nu)
            if model.actuator_trntype[i] == mujoco.mjtTrn.mjTRN_JOINT
            and model.jnt_type[model.actuator_trnid[i, 0]] == hinge
            and model.actuator_forcelimited[i]
            and model.actuator_forcerange[i, 1] > 0
        ],
        dtype=np.intp,
    )


def describe_actuation(model: mujoco.MjModel, mode: Actuation) -> dict:
    """What an action means in ``model`` (converted by :func:`apply_actuation`), per joint
    actuator, for an engine that replays a policy outside retarget: ``torque`` fractions of the
    torque limits, or ``pd`` targets (rad = action * ``scale``) with gains ``kp``, ``kd``."""
    if mode == "torque":
        return {"mode": "torque"}
    ids = _joint_actuators(model)
    kp = -model.actuator_biasprm[ids, 1]
    return {
        "mode": "pd",
        "scale": (model.actuator_gainprm[ids, 0] / kp).tolist(),
        "kp": kp.tolist(),
        "kd": (-model.actuator_biasprm[ids, 2]).tolist(),
    }
