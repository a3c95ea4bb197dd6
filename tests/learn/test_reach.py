"""Two-bone IK onto the controllers: on real library frames, arms bent away from the truth are
brought back so that the wrists sit where the controllers say, and estimates reach them, along
the arm of the skeleton the motion gives (not the average one)."""

from __future__ import annotations

import torch

from retarget.env.build import env_from_recipe
from retarget.geometry.heading import quat_to_matrix
from retarget.learn.pose_samples import (
    UNIT_OFFSETS,
    HeadsetFrame,
    forward_kinematics_globals,
    pose_targets,
    reads_controllers,
    sixd_to_matrix,
    skeleton_globals,
)
from retarget.learn.reach import ARMS, reach, wrist_targets
from retarget.motion import skeleton as sk
from retarget.motion.procedural import default_motions
from retarget.recipe import load
from retarget.registry.loader import load_plugins

REGISTRY = load_plugins(strict=True)


def _env(sensors: str = "three_point", clips=None):
    resolved = load(None, REGISTRY, shorthands={"sensors": sensors}, assignments=[])
    return env_from_recipe(resolved, num_envs=1, threads=1, clips=clips)


def _narrow_shouldered(clip):
    """``clip`` performed by someone whose shoulders are 8 cm narrower and whose arms are 7%
    shorter than the average skeleton's (a Bandai Namco performer's proportions)."""
    bones = clip.offsets.copy()
    for side in ("left", "right"):
        bones[sk.joint_index(f"{side}_shoulder")] *= 0.42
        for j in ("elbow", "wrist"):
            bones[sk.joint_index(f"{side}_{j}")] *= 0.93
    return clip.with_(offsets=bones)


def _bend(local: torch.Tensor, angle: float) -> torch.Tensor:
    axis = torch.tensor([0.3, 0.8, 0.5])
    axis = axis / axis.norm()
    q = torch.cat([torch.tensor([torch.cos(torch.tensor(angle / 2))]),
                   axis * torch.sin(torch.tensor(angle / 2))])  # fmt: skip
    turn = quat_to_matrix(q[None])[0]
    out = local.clone()
    for s, e, _ in ARMS:
        out[:, s] = out[:, s] @ turn
        out[:, e] = out[:, e] @ turn.T
    return out


def test_controllers_give_the_wrists_and_reach_restores_them() -> None:
    env = _env()
    lib = env.library
    rows = torch.arange(0, lib.num_frames, 7)
    hf = HeadsetFrame.of(lib.devices[rows][:, 0])
    truth = pose_targets(env, rows, hf)
    local = sixd_to_matrix(truth.rot6d)
    pos, glob = forward_kinematics_globals(truth.root_pos, local, truth.heights)
    ctrl = hf.poses_in(lib.devices[rows][:, 1:3])
    wrist_pos, wrist_rot = wrist_targets(ctrl, truth.heights)
    bones = UNIT_OFFSETS * truth.heights[:, None, None]
    for k, (_, _, w) in enumerate(ARMS):  # the mounts invert exactly
        assert (wrist_pos[:, k] - pos[:, w]).norm(dim=-1).max() < 2e-3
        assert (wrist_rot[:, k] - glob[w]).abs().max() < 1e-3
    bent = _bend(local, 0.6)
    before, _ = forward_kinematics_globals(truth.root_pos, bent, truth.heights)
    fixed = reach(truth.root_pos, bent, bones, wrist_pos, wrist_rot)
    after, g2 = forward_kinematics_globals(truth.root_pos, fixed, truth.heights)
    for k, (s, _, w) in enumerate(ARMS):
        assert (before[:, w] - pos[:, w]).norm(dim=-1).mean() > 0.05
        assert (after[:, w] - pos[:, w]).norm(dim=-1).max() < 3e-3
        assert (g2[w] - wrist_rot[:, k]).abs().max() < 1e-4
        assert (after[:, s] - pos[:, s]).norm(dim=-1).max() < 1e-5  # the shoulder stays
    det = torch.linalg.det(fixed)
    assert (det - 1).abs().max() < 1e-4  # still rotations


def test_an_estimator_with_reach_puts_its_hands_on_the_controllers() -> None:
    from retarget.learn.estimator import EstimatorLearner, EstimatorSettings

    env = _env()
    rows = torch.arange(0, env.library.num_frames, 11)
    far = EstimatorLearner(env, EstimatorSettings(hidden=(16,)), torch.Generator())
    near = EstimatorLearner(env, EstimatorSettings(hidden=(16,), reach=True), torch.Generator())
    near.net.load_state_dict(far.net.state_dict())
    errors = []
    for learner in (far, near):
        out, hf = learner.estimate_rows(rows)
        truth = pose_targets(env, rows, hf)
        pos, _ = forward_kinematics_globals(out.root_pos, out.matrices, truth.heights)
        wrists = [a[2] for a in ARMS]
        gap = pos[:, wrists] - truth.positions[:, wrists]
        errors.append(float(gap.norm(dim=-1).mean()))
    assert errors[1] < 0.5 * errors[0], errors


def test_reach_follows_the_persons_own_arm() -> None:
    """Devices synthesised on a skeleton of its own: reached along that skeleton the arm's
    rotations are the person's again (the character copies rotations), reached along the
    average skeleton they are not, although its wrist sits on the same point."""
    env = _env(clips=[_narrow_shouldered(c) for c in default_motions()])
    lib = env.library
    rows = torch.arange(0, lib.num_frames, 7)
    clip = torch.searchsorted(lib.start, rows, right=True) - 1
    hf = HeadsetFrame.of(lib.devices[rows][:, 0])
    truth = pose_targets(env, rows, hf)
    local = sixd_to_matrix(truth.rot6d)
    person = lib.bones[clip].float()
    ctrl = hf.poses_in(lib.devices[rows][:, 1:3])
    wrist_pos, wrist_rot = wrist_targets(ctrl, truth.heights)
    bent = _bend(local, 0.6)
    average = UNIT_OFFSETS * truth.heights[:, None, None]
    for bones, close in ((person, True), (average, False)):
        fixed = reach(truth.root_pos, bent, bones, wrist_pos, wrist_rot)
        reached, _ = skeleton_globals(truth.root_pos, fixed, bones)
        # on the character's (average) proportions, as the evaluation retargets the estimate
        on_average, _ = forward_kinematics_globals(truth.root_pos, fixed, truth.heights)
        for k, (_, _, w) in enumerate(ARMS):
            assert (reached[:, w] - wrist_pos[:, k]).norm(dim=-1).max() < 3e-3
            gap = (on_average[:, w] - truth.positions[:, w]).norm(dim=-1).mean()
            assert (gap < 5e-3) if close else (gap > 0.03), (k, float(gap))


def test_a_headset_alone_has_no_controllers_to_reach() -> None:
    from retarget.learn.estimator import EstimatorLearner, EstimatorSettings

    hmd, three = _env("hmd"), _env()
    assert reads_controllers(three) and not reads_controllers(hmd)
    settings = EstimatorSettings(hidden=(16,), reach=True)
    assert EstimatorLearner(three, settings, torch.Generator()).reach
    assert not EstimatorLearner(hmd, settings, torch.Generator()).reach
