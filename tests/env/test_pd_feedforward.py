"""The reference's PD feedforward: the inverse-dynamics torque of every library frame as a
target offset of the servos, and the ``reference_action`` base that carries it."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest
import torch

from retarget.env.build import env_from_recipe
from retarget.errors import PluginError
from retarget.motion.bvh_write import write_bvh
from retarget.motion.procedural import default_motions, idle_clip
from retarget.plugins.sensors.full_body import ReferenceAction
from retarget.recipe import load
from retarget.registry.loader import load_plugins
from retarget.sim.inverse_dynamics import reference_torques
from retarget.testing import fake_context


@pytest.fixture(scope="module")
def registry():
    return load_plugins()


def _env(registry, clip, folder):
    path = write_bvh(clip, folder / "clip.bvh")
    recipe = load("teacher", registry, shorthands={"motions": str(path)},
                  assignments=["env.num_envs=1"])  # fmt: skip
    return env_from_recipe(recipe, registry=registry, threads=1)


@pytest.fixture(scope="module")
def walk_env(registry, tmp_path_factory):
    return _env(registry, default_motions(names=("walk",))[0], tmp_path_factory.mktemp("walk"))


@pytest.fixture(scope="module")
def idle_env(registry, tmp_path_factory):
    return _env(registry, idle_clip(1.5), tmp_path_factory.mktemp("idle"))


def test_the_offset_is_the_supported_inverse_torque_and_damping_over_kp(walk_env) -> None:
    env = walk_env
    model, ref, lay = env.sim.model, env.reference, env.layout
    joints = np.asarray(model.actuator_trnid[:, 0], np.intp)
    qpos = np.tile(model.qpos0, (ref.num_frames, 1))
    qpos[:, : lay.nq] = ref.qpos64
    qvel = np.zeros((ref.num_frames, model.nv))
    qvel[:, : lay.nv] = ref.qvel64
    tau = reference_torques(model, qpos, qvel, env.sim.settings.control_dt, joints,
                            support=True)  # fmt: skip
    kp, kd = -model.actuator_biasprm[:, 1], -model.actuator_biasprm[:, 2]
    expected = (tau + kd * qvel[:, model.jnt_dofadr[joints]]) / kp
    reach = model.actuator_forcerange[:, 1] / kp
    expected = np.clip(expected, -reach, reach)
    got = ref.pose(torch.arange(ref.num_frames)).pd_feedforward
    assert got is not None and got.shape == (ref.num_frames, lay.nu)
    np.testing.assert_allclose(got.numpy(), expected, atol=2e-4)
    knees = [lay.actuator_names.index(n) for n in ("l_knee", "r_knee")]
    assert got[:, knees].abs().mean() > 0.01  # stance legs carry the body
    assert (got.abs() <= torch.as_tensor(reach, dtype=torch.float32) + 1e-6).all()


def test_the_base_with_feedforward_holds_a_standing_pose_the_plain_one_lets_sag(
    idle_env,
) -> None:
    """Open loop, no policy: a standing body given the reference's angles (plus its
    feedforward) as PD targets, frame after frame for a second; with the feedforward its
    joints stay nearer the reference."""
    env = idle_env
    model, ref, lay = env.sim.model, env.reference, env.layout
    scale = np.abs(model.jnt_range[model.actuator_trnid[:, 0]]).max(axis=1)
    qadr = model.jnt_qposadr[model.actuator_trnid[:, 0]]
    frames = min(ref.num_frames, 36)
    pose = ref.pose(torch.arange(frames))
    errors = []
    for share in (0.0, 1.0):
        data = mujoco.MjData(model)
        data.qpos[: lay.nq] = ref.qpos64[0]
        data.qvel[: lay.nv] = ref.qvel64[0]
        err = []
        for f in range(frames):
            target = ref.qpos64[f, qadr] + share * pose.pd_feedforward[f].double().numpy()
            data.ctrl[:] = np.clip(target / scale, -1, 1)
            for _ in range(env.sim.settings.substeps):
                mujoco.mj_step(model, data)
            err.append(np.abs(data.qpos[qadr] - ref.qpos64[f, qadr]).mean())
        errors.append(float(np.mean(err)))
    assert errors[1] < 0.6 * errors[0], errors


def test_the_sensor_adds_its_share_of_the_feedforward() -> None:
    ctx = fake_context()
    plain = ReferenceAction()
    fed = ReferenceAction(ReferenceAction.Config(feedforward=1.0))
    for sensor in (plain, fed):
        sensor.bind(ctx.layout)
    a, b = plain.observe(ctx), fed.observe(ctx)
    ranges = torch.tensor(ctx.layout.actuator_ranges).abs().amax(-1)
    inside = (a.abs() < 0.9) & (b.abs() < 0.9)  # away from the clamp at the joint range
    diff = (b - a) * ranges
    assert inside.any()
    torch.testing.assert_close(diff[inside], ctx.ref.future[1].pd_feedforward[inside],
                               atol=1e-5, rtol=1e-4)  # fmt: skip


def test_the_sensor_says_what_it_misses_without_a_feedforward() -> None:
    from dataclasses import replace

    ctx = fake_context()
    future = {k: replace(v, pd_feedforward=None) for k, v in ctx.ref.future.items()}
    ctx = replace(ctx, ref=replace(ctx.ref, future=future))
    fed = ReferenceAction(ReferenceAction.Config(feedforward=0.5))
    fed.bind(ctx.layout)
    with pytest.raises(PluginError, match="pd_feedforward"):
        fed.observe(ctx)
    plain = ReferenceAction()
    plain.bind(ctx.layout)
    assert plain.observe(ctx).shape == (ctx.num_envs, ctx.layout.nu)
