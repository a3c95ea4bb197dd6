"""The kinematic pose estimator: samples in the headset frame are exact, NLL training lowers
the loss on a fixed batch, the uncertainty has one value per joint, a run trains on a sample
budget and resumes exactly, eval reports it with the policies' metrics, ONNX matches."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import torch
from helpers import TINY

from retarget.cli.main import main
from retarget.env.build import env_from_recipe
from retarget.learn.estimator import (
    DEPLOYED_SIZE,
    DeployedEstimator,
    EstimatorLearner,
    EstimatorSettings,
)
from retarget.learn.pose_samples import J, mirror_body, mirror_devices, pose_targets, sensor_inputs
from retarget.recipe import load
from retarget.registry.loader import load_plugins
from retarget.train.checkpoint import load_checkpoint
from retarget.train.load import load_run

ESTIMATOR = TINY.replace("name: tiny", "name: est").split("algorithm:")[0] + """\
algorithm: {type: estimator, window: 4, hidden: [64], batch_size: 64, updates_per_iteration: 2}
env: {num_envs: 4}
sim: {threads: 1}
"""


@pytest.fixture(scope="module")
def env():
    registry = load_plugins()
    resolved = load(None, registry, shorthands={"sensors": "three_point"},
                    assignments=["sensors.0.past=3"])  # fmt: skip
    return env_from_recipe(resolved, num_envs=1, threads=1)


def test_targets_in_the_headset_frame_are_the_clip_joints(env) -> None:
    """The generated clips have the average proportions, so forward kinematics of the
    targets reproduces the library's joint positions moved into the headset frame."""
    rows = torch.arange(0, env.library.num_frames, 37)
    _, frame = sensor_inputs(env, rows)
    target = pose_targets(env, rows, frame)
    expected = frame.points_in(env.library.global_pos[rows])
    torch.testing.assert_close(target.positions, expected, atol=2e-4, rtol=0)
    head = frame.points_in(env.library.devices[rows, 0, :3][:, None])[:, 0]
    assert head[:, :2].abs().max() < 1e-5, "the headset is at the frame's origin"
    # mirrored samples are mirrored joints (left and right swapped, y flipped)
    flip = torch.ones(len(rows), dtype=torch.bool)
    _, mframe = sensor_inputs(env, rows, flip)
    mirrored = pose_targets(env, rows, mframe, flip).positions
    from retarget.motion import skeleton as sk

    lr = torch.tensor(sk.LEFT_RIGHT)
    world = env.library.global_pos[rows][:, lr] * torch.tensor([1.0, -1.0, 1.0])
    torch.testing.assert_close(mirrored, mframe.points_in(world), atol=2e-4, rtol=0)
    # mirroring twice changes nothing
    dev = env.library.devices[rows]
    torch.testing.assert_close(mirror_devices(mirror_devices(dev)), dev)
    r, q, c = env.library.root_pos[rows], env.library.local_rot[rows], env.library.contacts[rows]
    again = mirror_body(*mirror_body(r, q, c.float()))
    torch.testing.assert_close(again[1], q)


def test_nll_training_lowers_the_loss_on_a_fixed_batch(env) -> None:
    torch.manual_seed(0)  # the network's initial weights come from the global generator
    learner = EstimatorLearner(env, EstimatorSettings(hidden=(64,), lr=3e-3),
                               torch.Generator().manual_seed(0))  # fmt: skip
    inputs, _, target = learner.sample(256)
    learner.net.norm.update(inputs)
    first = float(learner.losses(inputs, target)["loss"].detach())
    for _ in range(150):
        parts = learner.losses(inputs, target)
        learner.optimizer.zero_grad()
        parts["loss"].backward()
        learner.optimizer.step()
    last = learner.losses(inputs, target)
    assert float(last["loss"].detach()) < first - 1.0, (first, float(last["loss"].detach()))
    assert float(last["mpjpe_mm"]) < 60.0
    out = DeployedEstimator(learner.net)(inputs[:5])
    assert out.shape == (5, DEPLOYED_SIZE) and DEPLOYED_SIZE == 3 + 6 * J + 2 + J
    std = out[:, -J:]
    assert (std > 0).all() and torch.isfinite(std).all()
    probs = out[:, 3 + 6 * J : 3 + 6 * J + 2]
    assert ((probs >= 0) & (probs <= 1)).all()


def test_an_estimator_run_trains_resumes_evaluates_and_exports(tmp_path: Path) -> None:
    recipe = tmp_path / "est.yaml"
    recipe.write_text(ESTIMATOR)
    assert main(["train", str(recipe), "--steps", "256", "--runs-dir", str(tmp_path),
                 "--no-tensorboard"]) == 0  # fmt: skip
    run = tmp_path / "est" / "latest"
    lock = (run / "recipe.lock.yaml").read_text()
    assert "past: 3" in lock and "num_envs: 1" in lock  # widened window, no physics envs
    loaded = load_run(run, load_plugins(), num_envs=2)
    assert loaded.algorithm.learner.iteration == 2  # 256 samples at 2 x 64 per iteration
    # resuming adds iterations on top, from the saved optimiser and generator
    assert main(["train", "--resume", str(run), "--steps", "128", "--no-tensorboard"]) == 0
    assert load_run(run, load_plugins(), num_envs=2).algorithm.learner.iteration == 3

    report_path = tmp_path / "eval.json"
    assert main(["eval", str(run), "--every", "60", "--max-seconds", "2",
                 "--json", str(report_path)]) == 0  # fmt: skip
    report = json.loads(report_path.read_text())
    assert report["method"].startswith("kinematic")
    overall = report["overall"]
    for key in ("mpjpe_mm", "mpjre_deg", "jerk_km_s3", "foot_skate_mm", "penetration_max_mm",
                "headset_cm", "controller_cm"):
        assert key in overall and np.isfinite(overall[key]), key

    # another run starts from its network (--init-from), with fresh optimiser and counters;
    # one with another window (other device features) is refused with the reason
    assert main(["train", str(recipe), "--init-from", str(run), "--set", "name=est2",
                 "--set", "env.devices=person", "--steps", "128", "--runs-dir", str(tmp_path),
                 "--no-tensorboard"]) == 0  # fmt: skip
    warm = load_run(tmp_path / "est2" / "latest", load_plugins(), num_envs=2)
    start = load_checkpoint(tmp_path / "est2" / "latest" / "checkpoints" / "ckpt-0000000.pt")
    source = load_run(run, load_plugins(), num_envs=1).algorithm.learner.net.state_dict()
    for key, value in start["algorithm"]["net"].items():
        if key != "norm.count":
            assert torch.equal(value, source[key]), key
    assert warm.algorithm.learner.iteration == 1  # 128 samples at 2 x 64, counted afresh
    rc = main(["train", str(recipe), "--init-from", str(run), "--set", "name=est3",
               "--set", "algorithm.window=6", "--steps", "64", "--runs-dir", str(tmp_path)])
    assert rc != 0

    # a pose estimator has no actions: play draws the character placed in its estimate, and
    # refuses a device recording (what drives a policy) by saying so
    assert main(["play", str(run), "--seconds", "0.5", "--out", str(tmp_path / "x.png")]) == 0
    assert (tmp_path / "x.png").stat().st_size > 1000
    recording = Path(__file__).parents[2] / "examples" / "recordings" / "walk_openxr.jsonl"
    refused = ["play", str(run), "--input", str(recording), "--out", str(tmp_path / "y.png")]
    assert main(refused) == 2

    ort = pytest.importorskip("onnxruntime")
    assert main(["export", str(run), "--onnx"]) == 0
    onnx_path = run / "export" / "policy.onnx"
    meta = json.loads(onnx_path.with_suffix(".json").read_text())
    assert meta["kind"] == "pose_estimator" and meta["outputs"][0]["name"] == "root_pos"
    loaded = load_run(run, load_plugins(), num_envs=2)
    inputs, _ = sensor_inputs(loaded.env, torch.arange(0, 200, 9))
    expected = DeployedEstimator(loaded.algorithm.learner.net).eval()(inputs).detach().numpy()
    (got,) = ort.InferenceSession(str(onnx_path)).run(None, {"obs": inputs.numpy()})
    assert got.shape == (len(inputs), DEPLOYED_SIZE) and meta["obs_dim"] == inputs.shape[1]
    np.testing.assert_allclose(got, expected, atol=1e-4, rtol=0)
    # the reach after it (on by default with controllers): network then reach.onnx gives what
    # retarget eval measures
    (after,) = meta["after"]
    assert after["name"] == "reach" and after["inputs"]["bones"] == ["batch", J, 3]
    learner = loaded.algorithm.learner
    rows = torch.arange(0, 200, 9)
    reached, frame = learner.estimate_rows(rows)
    lib = loaded.env.library
    ctrl = frame.poses_in(lib.devices[rows][:, 1:3])
    clip = torch.searchsorted(lib.start, rows, right=True) - 1
    (final,) = ort.InferenceSession(str(onnx_path.parent / after["onnx"])).run(None, {
        "estimate": got, "controllers": ctrl.float().numpy(),
        "bones": lib.bones[clip].float().numpy(), "height": lib.heights[clip].float().numpy()})
    np.testing.assert_allclose(final[:, 3 : 3 + 6 * J], reached.rot6d.reshape(len(rows), -1),
                               atol=1e-4, rtol=0)  # fmt: skip
    assert np.abs(final[:, 3 : 3 + 6 * J] - got[:, 3 : 3 + 6 * J]).max() > 1e-2  # it reached
    np.testing.assert_array_equal(final[:, 3 + 6 * J :], got[:, 3 + 6 * J :])


def test_two_stage_eval_follows_the_estimate_and_measures_the_truth(tmp_path: Path) -> None:
    """`eval TEACHER --estimator EST`: the imitator's reference is the estimate, the metrics
    compare with the true clips (a perfect tracker of a poor estimate still scores poorly)."""
    from helpers import TINY_TEACHER

    teacher = tmp_path / "teacher.yaml"
    teacher.write_text(TINY_TEACHER)
    est = tmp_path / "est.yaml"
    est.write_text(ESTIMATOR)
    for recipe, steps in ((teacher, "32"), (est, "128")):
        assert main(["train", str(recipe), "--steps", steps, "--runs-dir", str(tmp_path),
                     "--no-tensorboard"]) == 0  # fmt: skip
    assert main(["motion", "generate", "--out", str(tmp_path / "clips"), "--names", "walk"]) == 0
    clips = str(tmp_path / "clips")
    common = ["--motions", clips, "--every", "90", "--max-seconds", "1", "--num-envs", "4"]
    alone, both = tmp_path / "alone.json", tmp_path / "both.json"
    assert main(["eval", str(tmp_path / "teacher" / "latest"), *common,
                 "--json", str(alone)]) == 0  # fmt: skip
    assert main(["eval", str(tmp_path / "teacher" / "latest"), *common, "--json", str(both),
                 "--estimator", str(tmp_path / "est" / "latest")]) == 0  # fmt: skip
    a = json.loads(alone.read_text())["overall"]
    report = json.loads(both.read_text())
    assert report["method"].startswith("two-stage")
    b = report["overall"]
    assert np.isfinite(b["mpjpe_mm"]) and b["runs"] == a["runs"]
    # an estimator trained for 128 samples is far from the truth: following it costs accuracy
    assert b["g_mpjpe_mm"] > a["g_mpjpe_mm"]
    # a policy run given as the estimator is refused by name
    assert main(["eval", str(tmp_path / "teacher" / "latest"), *common,
                 "--estimator", str(tmp_path / "teacher" / "latest")]) == 2  # fmt: skip


def test_lost_controllers_change_only_what_the_sensors_see(env) -> None:
    rows = torch.arange(10, 200, 17)
    w = len(env.window_offsets)
    plain, _ = sensor_inputs(env, rows)
    none, _ = sensor_inputs(env, rows, frozen_from=torch.full((len(rows), 2), w))
    torch.testing.assert_close(none, plain)
    lost, frame = sensor_inputs(env, rows, frozen_from=torch.zeros(len(rows), 2, dtype=torch.long))
    assert not torch.allclose(lost, plain)
    # the targets do not depend on what the devices reported
    plain_frame = sensor_inputs(env, rows)[1]
    torch.testing.assert_close(pose_targets(env, rows, frame).positions,
                               pose_targets(env, rows, plain_frame).positions)  # fmt: skip


def test_a_scene_aware_estimator_reads_the_height_map_of_each_samples_clip() -> None:
    registry = load_plugins()
    resolved = load(None, registry, shorthands={"sensors": "three_point"},
                    assignments=["sensors.0.past=3", "observers=[height_map]",
                                 "scene={type: boxes, preset: stepping_path}"])  # fmt: skip
    env = env_from_recipe(resolved, num_envs=1, threads=1)
    rows = torch.arange(0, env.library.num_frames, 7)
    inputs, _ = sensor_inputs(env, rows)
    heights = inputs[:, -120:]
    assert inputs.shape[1] == env.sensors[0].spec(env.layout).size + 120
    assert (heights.abs() > 0.05).any(), "some samples stand near a box"
    learner = EstimatorLearner(env, EstimatorSettings(hidden=(32,), batch_size=64),
                               torch.Generator().manual_seed(0))  # fmt: skip
    stats = learner.train_iteration()
    assert np.isfinite(stats["loss"])


def test_the_estimate_as_a_sensor_composes_in_a_recipe(tmp_path: Path) -> None:
    """`estimated_body` gives a policy the estimator run's output, exactly what the run's
    deployed network gives for the same device window; a student trains and exports with it."""
    from retarget.learn.columns import source_columns

    recipe = tmp_path / "est.yaml"
    recipe.write_text(ESTIMATOR)
    assert main(["train", str(recipe), "--steps", "128", "--runs-dir", str(tmp_path),
                 "--no-tensorboard"]) == 0  # fmt: skip
    est_run = tmp_path / "est" / "latest"
    student = tmp_path / "student.yaml"
    student.write_text(TINY.replace("name: tiny", "name: two_stage").replace(
        "sensors: [three_point]",
        f"sensors: [three_point, {{type: estimated_body, estimator: {est_run}}}]"))  # fmt: skip
    assert main(["train", str(student), "--steps", "32", "--runs-dir", str(tmp_path),
                 "--no-tensorboard"]) == 0  # fmt: skip
    registry = load_plugins()
    loaded = load_run(tmp_path / "two_stage" / "latest", registry, num_envs=2)
    env = loaded.env
    frames = torch.tensor([5, 30])
    obs = env.place(torch.zeros(2, dtype=torch.long), frames)["actor"]
    got = obs[:, source_columns(env, "actor", "estimated_body")]
    estimator = load_run(est_run, registry, num_envs=1)
    rows = estimator.env.library.rows(torch.zeros(2, dtype=torch.long), frames)[:, 0]
    inputs, _ = sensor_inputs(estimator.env, rows)
    want = DeployedEstimator(estimator.algorithm.learner.net).eval()(inputs).detach()
    torch.testing.assert_close(got, want, atol=1e-5, rtol=1e-5)
    assert main(["export", str(tmp_path / "two_stage" / "latest"), "--onnx"]) == 0
    folder = tmp_path / "two_stage" / "latest" / "export"
    meta = json.loads((folder / "policy.json").read_text())
    (stage,) = meta["stages"]
    assert stage["source"] == "estimated_body" and stage["inputs"][0]["name"] == "three_point"
    ort = pytest.importorskip("onnxruntime")
    (first,) = ort.InferenceSession(str(folder / stage["onnx"])).run(None, {"obs": inputs.numpy()})
    np.testing.assert_allclose(first, want.numpy(), atol=1e-5)


def test_the_estimator_sensor_locks_the_checkpoint_it_reads(tmp_path: Path, capsys) -> None:
    """A two-stage run's lock names the estimator run's directory and checkpoint (not its
    moving `latest`), as a student's names its teacher's; a run that is not a pose estimator
    is refused before anything is built."""
    import yaml

    recipe = tmp_path / "est.yaml"
    recipe.write_text(ESTIMATOR)
    assert main(["train", str(recipe), "--steps", "128", "--runs-dir", str(tmp_path),
                 "--no-tensorboard", "--checkpoint-every", "1"]) == 0  # fmt: skip
    est_run = (tmp_path / "est" / "latest").resolve()
    first = sorted((est_run / "checkpoints").glob("ckpt-*.pt"))[-1].name
    student = tmp_path / "student.yaml"
    student.write_text(TINY.replace("name: tiny", "name: two_stage").replace(
        "sensors: [three_point]",
        f"sensors: [three_point, {{type: estimated_body, estimator: {tmp_path}/est/latest}}]"))
    assert main(["train", str(student), "--steps", "32", "--runs-dir", str(tmp_path),
                 "--no-tensorboard"]) == 0  # fmt: skip
    lock = yaml.safe_load((tmp_path / "two_stage" / "latest" / "recipe.lock.yaml").read_text())
    (sensor,) = [s for s in lock["sensors"] if s["type"] == "estimated_body"]
    assert sensor["estimator"] == str(est_run) and sensor["checkpoint"] == f"checkpoints/{first}"

    bad = tmp_path / "bad.yaml"
    bad.write_text(TINY.replace("name: tiny", "name: bad").replace(
        "sensors: [three_point]",
        "sensors: [three_point, {type: estimated_body, estimator: "
        f"{tmp_path}/two_stage/latest}}]"))
    capsys.readouterr()
    assert main(["train", str(bad), "--steps", "32", "--runs-dir", str(tmp_path),
                 "--no-tensorboard"]) == 2  # fmt: skip
    assert "not a pose estimator" in capsys.readouterr().err
