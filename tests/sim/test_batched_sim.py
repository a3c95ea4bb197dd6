"""BatchedSim against plain MuJoCo: same physics, per-env blow-up detection, subset resets."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest
import torch

from retarget.sim import BatchedSim, SimSettings
from retarget.testing.fakes import tiny_world


@pytest.fixture
def sim() -> BatchedSim:
    world = tiny_world()
    return BatchedSim(world.model, world.layout, 6, SimSettings(threads=2))


def _actions(n: int, nu: int, steps: int) -> np.ndarray:
    return np.random.default_rng(0).uniform(-0.3, 0.3, size=(steps, n, nu))


def test_matches_a_plain_mujoco_loop(sim: BatchedSim) -> None:
    acts = _actions(sim.num_envs, sim.layout.nu, 20)
    data = mujoco.MjData(sim.model)
    mujoco.mj_forward(sim.model, data)
    for a in acts:
        sim.step(torch.from_numpy(a))
        data.ctrl[:] = a[2]
        mujoco.mj_step(sim.model, data, sim.settings.substeps)
    np.testing.assert_allclose(sim.raw("qpos")[2], data.qpos, atol=1e-9)
    head = sim.layout.site("head")
    site = sim.layout.site_ids[head]
    np.testing.assert_allclose(sim.state.site_pos[2, head].numpy(), data.site_xpos[site], atol=1e-5)
    body = sim.layout.body_ids[1]
    np.testing.assert_allclose(sim.state.body_quat[2, 1].numpy(), data.xquat[body], atol=1e-6)


def test_state_tensors_are_live_views(sim: BatchedSim) -> None:
    qpos = sim.state.qpos
    z0 = float(qpos[0, 2])
    for _ in range(10):
        sim.step(np.zeros((sim.num_envs, sim.layout.nu)))
    assert sim.state.qpos is qpos and float(qpos[0, 2]) != z0


def test_contact_forces_hold_the_weight(sim: BatchedSim) -> None:
    for _ in range(150):
        sim.step(np.zeros((sim.num_envs, sim.layout.nu)))
    weight = sim.model.body_mass.sum() * 9.81
    total = sim.state.contact_force.sum(dim=1)
    assert torch.all(total > 0.5 * weight), (total, weight)


def test_non_finite_env_is_flagged_alone(sim: BatchedSim) -> None:
    reference = BatchedSim(sim.model, sim.layout, sim.num_envs, sim.settings)
    acts = _actions(sim.num_envs, sim.layout.nu, 6)
    for a in acts[:3]:
        sim.step(a)
        reference.step(a)
    sim.raw("qvel")[3, 0] = np.nan
    flagged = []
    for a in acts[3:]:
        flagged.append(sim.step(a))
        reference.step(a)
    assert flagged[0].tolist() == [False, False, False, True, False, False]
    assert sim.bad_count == 1
    others = [0, 1, 2, 4, 5]
    np.testing.assert_allclose(sim.raw("qpos")[others], reference.raw("qpos")[others], atol=1e-12)
    assert torch.isfinite(sim.state.qpos).all()


def test_huge_velocity_is_flagged(sim: BatchedSim) -> None:
    sim.raw("qvel")[1, 6] = 1e9
    bad = sim.step(np.zeros((sim.num_envs, sim.layout.nu)))
    assert bad[1] and bad.sum() == 1


def test_reset_subset(sim: BatchedSim) -> None:
    for _ in range(5):
        sim.step(np.zeros((sim.num_envs, sim.layout.nu)))
    before = sim.raw("qpos").copy()
    target = before[[1, 4]].copy()
    target[:, 0] += 3.0
    sim.reset(np.array([1, 4]), target)
    np.testing.assert_allclose(sim.raw("qpos")[[1, 4]], target)
    np.testing.assert_allclose(sim.raw("qpos")[[0, 2, 3, 5]], before[[0, 2, 3, 5]])
    root = sim.layout.body_ids[0]
    np.testing.assert_allclose(sim.state.body_pos[[1, 4], 0, 0].numpy(), target[:, 0], atol=1e-5)
    assert root >= 1


def test_body_velocities_match_finite_differences(sim: BatchedSim) -> None:
    """Body-origin velocities agree with differentiating body positions along qvel."""
    for a in _actions(sim.num_envs, sim.layout.nu, 8):
        sim.step(a)
    sim.batch.forward(np.array([1]))  # derived fields of the current state, not the last substep
    sim.gather()
    h = 1e-6
    data = mujoco.MjData(sim.model)
    data.qpos[:] = sim.raw("qpos")[1]
    mujoco.mj_kinematics(sim.model, data)
    before = data.xpos.copy()
    mujoco.mj_integratePos(sim.model, data.qpos, sim.raw("qvel")[1], h)
    mujoco.mj_kinematics(sim.model, data)
    expected = (data.xpos - before)[list(sim.layout.body_ids)] / h
    np.testing.assert_allclose(sim.state.body_linvel[1].numpy(), expected, atol=1e-3)
