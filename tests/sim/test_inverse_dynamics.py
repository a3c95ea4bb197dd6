"""The planner's inverse-dynamics feedforward: torques only where a joint's bodies touch
nothing, and the servo that gets them holds a limb where the plain one sags."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from retarget.env.build import env_from_recipe
from retarget.motion.bvh_write import write_bvh
from retarget.motion.procedural import idle_clip
from retarget.recipe import load
from retarget.registry.loader import load_plugins
from retarget.sim.actuation import describe_actuation
from retarget.sim.inverse_dynamics import reference_torques, subtree_masks


@pytest.fixture(scope="module")
def env(tmp_path_factory):
    clip = write_bvh(idle_clip(1.0), tmp_path_factory.mktemp("clips") / "idle.bvh")
    registry = load_plugins()
    recipe = load("teacher", registry, shorthands={"motions": str(clip)},
                  assignments=["env.num_envs=1"])  # fmt: skip
    return env_from_recipe(recipe, registry=registry, threads=1)


def _joints(env) -> tuple[np.ndarray, list[str]]:
    model = env.sim.model
    ids = np.asarray(model.actuator_trnid[: env.layout.nu, 0], np.intp)
    return ids, [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) for j in ids]


def _frames(env, lift: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    ref, nq, nv = env.reference, env.sim.model.nq, env.sim.model.nv
    qpos = np.zeros((5, nq))
    qpos[:, : env.layout.nq] = ref.qpos64[:5]
    qpos[:, env.layout.nq :] = env.sim.model.qpos0[env.layout.nq :]
    qpos[:, 2] += lift
    return qpos, np.zeros((5, nv))


def test_subtree_of_the_root_joint_is_the_whole_body(env) -> None:
    model = env.sim.model
    ids, names = _joints(env)
    masks = subtree_masks(model, ids)
    knee = names.index("l_knee")
    foot = [b for b in range(model.nbody) if masks[knee, b]]
    assert len(foot) >= 2 and int(model.jnt_bodyid[ids[knee]]) in foot
    assert not masks[knee, int(model.jnt_bodyid[ids[names.index("r_knee")]])]


def test_standing_legs_get_nothing_arms_get_their_gravity(env) -> None:
    ids, names = _joints(env)
    qpos, qvel = _frames(env)
    tau = reference_torques(env.sim.model, qpos, qvel, 1 / 36, ids)
    legs = [i for i, n in enumerate(names) if n.startswith(("l_hip", "r_knee", "l_ankle"))]
    assert np.all(tau[:, legs] == 0.0)
    # at rest, the torque an untouched joint needs is its gravity load
    data = mujoco.MjData(env.sim.model)
    data.qpos[:] = qpos[0]
    mujoco.mj_forward(env.sim.model, data)
    arm = [i for i, n in enumerate(names) if "shoulder" in n or "spine" in n]
    dofs = env.sim.model.jnt_dofadr[ids[arm]]
    np.testing.assert_allclose(tau[0, arm], data.qfrc_bias[dofs], rtol=1e-6, atol=1e-6)
    assert np.abs(tau[0, arm]).max() > 1.0


def test_a_body_in_the_air_gets_torques_at_every_joint(env) -> None:
    ids, _ = _joints(env)
    qpos, qvel = _frames(env, lift=1.0)
    tau = reference_torques(env.sim.model, qpos, qvel, 1 / 36, ids)
    assert (np.abs(tau) > 0).mean() > 0.9


def test_the_feedforward_target_holds_the_spine_where_the_plain_one_sags(env) -> None:
    """A pose held by the PD servos, the root pinned (a huge armature on its degrees of
    freedom): with ``tau / kp`` added to the targets the spine ends closer to the pose than
    with the pose itself as target."""
    model = env.sim.model.__copy__()
    model.dof_armature[:6] = 1e9
    ids, names = _joints(env)
    qpos, qvel = _frames(env, lift=1.0)
    tau = reference_torques(env.sim.model, qpos, qvel, 1 / 36, ids)[0]
    servo = describe_actuation(model, "pd")
    kp, scale = np.asarray(servo["kp"]), np.asarray(servo["scale"])
    spine = names.index("spine_y")
    qadr = model.jnt_qposadr[ids]
    errors = []
    for extra in (np.zeros_like(tau), tau / kp):
        data = mujoco.MjData(model)
        data.qpos[:] = qpos[0]
        target = (qpos[0, qadr] + extra) / scale
        for _ in range(400):
            data.ctrl[: len(ids)] = target
            mujoco.mj_step(model, data)
        errors.append(abs(data.qpos[qadr[spine]] - qpos[0, qadr[spine]]))
    assert errors[1] < 0.3 * errors[0], errors


def test_an_empty_reference_gives_no_rows(env) -> None:
    ids, _ = _joints(env)
    empty = np.zeros((0, env.sim.model.nq)), np.zeros((0, env.sim.model.nv))
    assert reference_torques(env.sim.model, *empty, 1 / 36, ids).shape == (0, len(ids))


def test_support_loads_the_stance_legs_and_a_standing_body_holds_its_pose(env) -> None:
    """``support``: the legs carry the body, so they get torques; standing on the floor with
    ``q + tau / kp`` as targets the joints stay closer to the pose than with ``q``."""
    model = env.sim.model
    ids, names = _joints(env)
    qpos, qvel = _frames(env)
    tau = reference_torques(model, qpos, qvel, 1 / 36, ids, support=True)[0]
    knees = [names.index("l_knee"), names.index("r_knee")]
    assert np.all(np.abs(tau[knees]) > 1.0), tau[knees]
    servo = describe_actuation(model, "pd")
    kp, scale = np.asarray(servo["kp"]), np.asarray(servo["scale"])
    qadr = model.jnt_qposadr[ids]
    errors = []
    for extra in (np.zeros_like(tau), tau / kp):
        data = mujoco.MjData(model)
        data.qpos[:] = qpos[0]
        for _ in range(100):
            data.ctrl[: len(ids)] = (qpos[0, qadr] + extra) / scale
            mujoco.mj_step(model, data)
        errors.append(np.abs(data.qpos[qadr] - qpos[0, qadr]).mean())
    assert errors[1] < 0.3 * errors[0], errors


def test_a_directory_planned_before_the_fields_existed_keeps_its_key() -> None:
    """Fields added later, at the value that plans as before, leave the settings key alone
    (an older expert directory resumes); turned on, they change it."""
    from retarget.expert import ExpertConfig
    from retarget.expert.config import ADDED_LATER
    from retarget.expert.store import settings_key

    planner = ExpertConfig(**ADDED_LATER).model_dump(mode="json")
    old = {k: v for k, v in planner.items() if k not in ADDED_LATER}
    recipe = {"character": "human"}
    assert settings_key({"recipe": recipe, "planner": old}) == settings_key(
        {"recipe": recipe, "planner": planner})
    changed = {"inverse_ff": 1.0, "inverse_support": True, "lookahead_share": 0.25}
    assert set(changed) == set(ADDED_LATER)
    for field in ADDED_LATER:
        on = {**planner, field: changed[field]}
        assert settings_key({"recipe": recipe, "planner": on}) != settings_key(
            {"recipe": recipe, "planner": planner})
