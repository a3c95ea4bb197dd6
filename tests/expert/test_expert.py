"""The tracking expert: real MuJoCo planning, its files, `retarget expert` and cloning it."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import torch
from helpers import REPO

from retarget.env.build import env_from_recipe
from retarget.errors import PluginError, RecipeError
from retarget.expert import BeamTracker, ExpertConfig
from retarget.expert.store import load_track, write_track
from retarget.motion.bvh_write import write_bvh
from retarget.motion.procedural import idle_clip
from retarget.recipe import load
from retarget.registry.loader import load_plugins
from retarget.train.checkpoint import load_checkpoint

SMALL = {"samples": 48, "beam": 6, "keep": 3}


@pytest.fixture(scope="module")
def registry():
    return load_plugins()


@pytest.fixture(scope="module")
def clip_file(tmp_path_factory) -> Path:
    return write_bvh(idle_clip(1.5), tmp_path_factory.mktemp("clips") / "idle.bvh")


def _env(registry, clip_file: Path, *sets: str):
    recipe = load("teacher", registry, shorthands={"motions": str(clip_file)},
                  assignments=["env.num_envs=1", *sets])  # fmt: skip
    return env_from_recipe(recipe, registry=registry, threads=1)


@pytest.fixture(scope="module")
def track(registry, clip_file):
    env = _env(registry, clip_file)
    return env, BeamTracker(env, ExpertConfig(**SMALL)).track(0, seconds=1.0)


def test_tracks_a_clip_it_never_saw(track) -> None:
    _, tr = track
    m = tr.metrics()
    assert tr.frames == 37 and tr.actions.shape == (36, tr.actions.shape[1])
    assert m["success_clip"] and m["g_mpjpe_mm"] < 120, m
    assert m["cpu_seconds"] > 0 and m["cpu_s_per_motion_s"] > 0
    assert len(tr.demos["frame"]) == 12 * 3  # 12 segments x 3 kept members


def test_its_actions_replay_to_its_states_in_the_env(track) -> None:
    """The plan is physically consistent: the env itself, stepped with the plan's actions
    from the placed frame, goes through the plan's states."""
    env, tr = track
    env.place(torch.tensor([0]), torch.tensor([0]))
    for t, action in enumerate(tr.actions[:18]):
        env.step_physics(torch.from_numpy(action[None]))
        np.testing.assert_allclose(env.sim.raw("qpos")[0], tr.qpos[t + 1], atol=1e-5)


def test_refuses_torque_actuation(registry, clip_file) -> None:
    env = _env(registry, clip_file, "sim.actuation=torque")
    with pytest.raises(PluginError, match="actuation"):
        BeamTracker(env, ExpertConfig(**SMALL))


def _shapes(env):
    sim = env.sim
    s = {k: tuple(sim.raw(k).shape[1:]) for k in sim.STATE_FIELDS}
    return {"nq": s["qpos"][0], "nv": s["qvel"][0], "nu": env.action_dim, "state_shapes": s}


def test_files_round_trip_and_hostile_ones_are_refused(track, tmp_path) -> None:
    env, tr = track
    (tmp_path / "clips").mkdir()
    figures = write_track(tmp_path, "idle", tr, {"key": "k"})
    assert figures["success_clip"] and (tmp_path / "clips" / "idle.json").exists()
    data = load_track(tmp_path / "clips" / "idle.npz", **_shapes(env))
    np.testing.assert_array_equal(data["actions"], tr.actions)
    good = dict(data)
    for why, change in {
        "shape": {"actions": good["actions"][:, :3]},
        "non-finite": {"qpos": np.full_like(good["qpos"], np.nan)},
        "outside": {"demo_frame": good["demo_frame"] + 10_000},
    }.items():
        bad = tmp_path / f"{why}.npz"
        np.savez(bad, **{**good, **change})
        with pytest.raises(RecipeError, match="refused") as info:
            load_track(bad, **_shapes(env))
        assert str(bad) in str(info.value)
    pickled = tmp_path / "pickled.npz"
    np.savez(pickled, **{**good, "qpos": np.array([object()], dtype=object)})
    with pytest.raises(RecipeError, match="refused"):
        load_track(pickled, **_shapes(env))


def _cli(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "retarget", *args], cwd=cwd,
                          capture_output=True, text=True, timeout=600)  # fmt: skip


def test_cli_plans_resumes_and_a_student_clones_it(clip_file, tmp_path) -> None:
    out = tmp_path / "expert"
    small = [f"--planner={k}={v}" for k, v in SMALL.items()]
    first = _cli("expert", str(clip_file), "--out", str(out), "--seconds", "0.5", *small,
                 cwd=tmp_path)  # fmt: skip
    assert first.returncode == 0, first.stderr
    report = json.loads((out / "report.json").read_text())
    assert report["summary"]["clips"] == 1 and "idle" in report["clips"]
    assert report["clips"]["idle"]["reference_drop_beyond_fall_mm_s"] == 0.0  # standing still
    assert "success_clip=1.000" in first.stdout
    picture = subprocess.run(
        [sys.executable, str(REPO / "benchmarks" / "expert_picture.py"), str(out), "idle",
         "--out", str(tmp_path / "plan.png"), "--frames", "4", "--size", "64", "48"],
        cwd=tmp_path, capture_output=True, text=True, timeout=600)  # fmt: skip
    assert picture.returncode == 0, picture.stderr
    png = (tmp_path / "plan.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    assert int.from_bytes(png[16:20], "big") >= 4 * 64 and int.from_bytes(png[20:24], "big") == 48
    missing = subprocess.run(
        [sys.executable, str(REPO / "benchmarks" / "expert_picture.py"), str(out), "walk",
         "--out", str(tmp_path / "x.png")], cwd=tmp_path, capture_output=True, text=True)
    assert missing.returncode != 0 and "'walk' matches 0 planned clips" in missing.stderr
    again = _cli("expert", str(clip_file), "--out", str(out), "--seconds", "0.5", *small,
                 cwd=tmp_path)  # fmt: skip
    assert again.returncode == 0 and "1 planned before, 0 to plan" in again.stderr
    other = _cli("expert", str(clip_file), "--out", str(out), "--planner", "samples=64",
                 cwd=tmp_path)  # fmt: skip
    assert other.returncode != 0 and "expert.json" in other.stderr
    said = " ".join(other.stderr.split())
    assert "planner.samples: 48 in the directory, 64 now" in said, other.stderr
    second = tmp_path / "idle_again.bvh"
    second.write_bytes(clip_file.read_bytes())
    both = _cli("expert", str(second), str(clip_file), "--out", str(out), "--seconds", "0.5",
                *small, cwd=tmp_path)  # fmt: skip
    assert both.returncode == 0 and "2 clips: 1 planned before, 1 to plan" in both.stderr
    runs = tmp_path / "runs"
    train = _cli("train", "--sensors", "three_point", "--expert", str(out), "--steps", "512",
                 "--num-envs", "8", "--threads", "1", "--runs-dir", str(runs), cwd=tmp_path)
    assert train.returncode == 0, train.stderr + train.stdout
    run = next(runs.glob("*/latest"))
    lock = (run / "recipe.lock.yaml").read_text()
    assert "type: expert_bc" in lock and "actuation: pd" in lock
    assert str(out / "motions") in lock
    ckpt = sorted((run / "checkpoints").glob("ckpt-*.pt"))[-1]
    state = load_checkpoint(ckpt)
    assert state["algorithm"]["env_steps"] >= 512
    for f in (out / "clips").iterdir():  # a cloned student evaluates without the expert's data
        f.unlink()
    ev = _cli("eval", str(run), "--motions", str(clip_file), "--num-envs", "2", cwd=tmp_path)
    assert ev.returncode == 0, ev.stderr
    dino = _cli("train", "--character", "dino", "--expert", str(out), "--steps", "64",
                "--runs-dir", str(runs), cwd=tmp_path)  # fmt: skip
    assert dino.returncode != 0 and "--character human" in dino.stderr + dino.stdout


def test_velocity_feedforward_cancels_the_servo_damping(track) -> None:
    """``velocity_ff`` (on by default) adds kd/kp x the reference joint velocity to the
    target, so a PD servo moving at the reference speed has no damping lag; 0 adds nothing."""
    from retarget.sim.actuation import describe_actuation

    env, _ = track
    on = BeamTracker(env, ExpertConfig(**SMALL))  # the default
    off = BeamTracker(env, ExpertConfig(**SMALL, velocity_ff=0.0))
    pd = describe_actuation(on.sim.model, "pd")
    row = int(env.library.start[0]) + 10
    model = on.sim.model
    dof = model.jnt_dofadr[model.actuator_trnid[: env.layout.nu, 0]]
    qd = env.reference.qvel64[row][dof]
    want = np.asarray(pd["kd"]) / np.asarray(pd["kp"]) * qd / np.asarray(pd["scale"])
    np.testing.assert_allclose(on._feedforward(row), want, rtol=1e-6, atol=1e-12)
    assert np.abs(want).max() > 0  # the idle clip moves: the check is not 0 == 0
    assert not off._feedforward(row).any()


def test_a_rescue_plans_again_only_the_segments_in_trouble(track) -> None:
    """``rescue.threshold`` re-plans a segment whose best sample ends its lookahead farther
    than that from the reference: a threshold no sample can meet re-plans every segment, an
    unreachable one none, and off (0, the default) counts none."""
    env, plain = track
    assert plain.rescued == 0 and plain.metrics()["rescued_segments"] == 0
    always = BeamTracker(env, ExpertConfig(**SMALL, rescue={"threshold": 1e-6, "lookahead": 3}))
    tr = always.track(0, seconds=0.5)
    segments = -(-(tr.frames - 1) // ExpertConfig().segment)
    assert tr.rescued == segments == always.rescues
    assert tr.metrics()["success_clip"]
    never = BeamTracker(env, ExpertConfig(**SMALL, rescue={"threshold": 5.0}))
    assert never.track(0, seconds=0.5).rescued == 0


def test_a_residual_teacher_cloned_from_it_fine_tunes_with_ppo(clip_file, tmp_path) -> None:
    """``retarget train teacher --expert DIR`` with the teacher's residual, then PPO from it:
    the PPO run starts acting exactly as the clone did (same network, same base added), and a
    fine-tune that would add another base is refused."""
    from retarget.train.load import load_run

    out = tmp_path / "expert"
    small = [f"--planner={k}={v}" for k, v in SMALL.items()]
    assert _cli("expert", str(clip_file), "--out", str(out), "--seconds", "0.5", *small,
                "--set", "motions.level_feet=false", cwd=tmp_path).returncode == 0  # fmt: skip
    runs = tmp_path / "runs"
    common = ["--num-envs", "8", "--threads", "1", "--runs-dir", str(runs), "--no-tensorboard"]
    clone = _cli("train", "teacher", "--expert", str(out), "--set", "name=clone", "--set",
                 "algorithm.residual=reference_action", "--steps", "256", *common, cwd=tmp_path)
    assert clone.returncode == 0, clone.stderr + clone.stdout
    lock = (runs / "clone" / "latest" / "recipe.lock.yaml").read_text()
    assert "level_feet: false" in lock  # the clips as the expert read them
    tuned = _cli("train", "teacher", "--motions", str(clip_file), "--init-from",
                 str(runs / "clone" / "latest"), "--set", "name=tuned", "--steps", "64", *common,
                 cwd=tmp_path)  # fmt: skip
    assert tuned.returncode == 0, tuned.stderr + tuned.stdout

    registry = load_plugins()
    a = load_run(runs / "clone" / "latest", registry, num_envs=2)
    b = load_run(runs / "tuned" / "latest", registry, num_envs=2,
                 checkpoint=runs / "tuned" / "latest" / "checkpoints" / "ckpt-0000000.pt")
    obs = {k: v.float() for k, v in b.env.reset().items()}
    from retarget.learn.columns import source_columns
    base = obs["actor"][:, source_columns(a.env, "actor", "reference_action")]
    assert torch.allclose(a.algorithm.act(obs), b.algorithm.act(obs), atol=1e-5)
    assert not torch.allclose(a.algorithm.act(obs), (a.algorithm.act(obs) - base).clamp(-1, 1))

    other = _cli("train", "teacher", "--motions", str(clip_file), "--init-from",
                 str(runs / "clone" / "latest"), "--set", "algorithm.residual=null",
                 "--steps", "32", *common, cwd=tmp_path)  # fmt: skip
    assert other.returncode != 0 and "algorithm.residual" in other.stderr + other.stdout


def test_a_clone_learns_only_the_frames_before_the_expert_failed() -> None:
    """A planned path whose bodies drift past PHC's 0.5 m from frame 6 on is replayed only up
    to frame 5; the beam members whose segment reaches frame 6 are left out too."""
    from retarget.learn.expert_bc import ExpertWindows, tracked_part

    frames, nu = 12, 2
    drift = np.where(np.arange(frames) >= 6, 0.8, 0.1)  # metres, every body
    ref = np.zeros((frames, 3, 3))
    body = ref + drift[:, None, None] * np.array([1.0, 0.0, 0.0])
    clip = {"qpos": np.arange(frames, dtype=float)[:, None], "qvel": np.zeros((frames, 1)),
            "actions": np.ones((frames - 1, nu), np.float32), "body_pos": body,
            "ref_body_pos": ref, "demo_frame": np.array([0, 3, 4]),
            "demo_steps": np.array([3, 2, 3]), "demo_prev_action": np.zeros((3, nu)),
            "demo_actions": np.ones((3, 3, nu)), "demo_state_qpos": np.zeros((3, 1)),
            "demo_state_qvel": np.zeros((3, 1))}  # fmt: skip
    cut = tracked_part(clip)
    assert len(cut["qpos"]) == 6 and len(cut["actions"]) == 5
    assert cut["demo_frame"].tolist() == [0, 3]  # the third ends at frame 7
    windows = ExpertWindows([cut], ())
    drawn = windows.draw(500, np.random.default_rng(0), demo_share=0.0, length=4)
    assert (drawn["frame"] + drawn["steps"]).max() == 5  # the last step reaches frame 5
    assert np.isin(drawn["qpos"][:, 0], np.arange(6)).all()
    assert tracked_part({**clip, "body_pos": ref})["qpos"].shape == (frames, 1)  # kept whole
    with pytest.raises(ValueError, match="no tracked step"):
        ExpertWindows([tracked_part({**clip, "body_pos": ref + 1.0})], ())


def test_inverse_feedforward_reaches_the_targets_with_or_without_the_velocity_term(track):
    """``inverse_ff`` adds its share of the reference's torque over kp to the target of the
    rows of the clip being planned, whether ``velocity_ff`` is on or off."""
    from retarget.sim.actuation import describe_actuation
    from retarget.sim.inverse_dynamics import reference_torques

    env, _ = track
    half = BeamTracker(env, ExpertConfig(**SMALL, velocity_ff=0.0, inverse_ff=0.5))
    half.track(0, seconds=0.3)
    model = half.sim.model
    start = int(env.library.start[0])
    row = start + 5
    qpos = np.tile(model.qpos0, (12, 1))
    qpos[:, : env.layout.nq] = env.reference.qpos64[start : start + 12]
    qvel = np.zeros((12, model.nv))
    qvel[:, : env.layout.nv] = env.reference.qvel64[start : start + 12]
    joints = model.actuator_trnid[: env.layout.nu, 0]
    tau = reference_torques(model, qpos, qvel, env.sim.settings.control_dt, joints)[5]
    pd = describe_actuation(model, "pd")
    want = 0.5 * tau / (np.asarray(pd["kp"]) * np.asarray(pd["scale"]))
    np.testing.assert_allclose(half._feedforward(row), want, rtol=1e-6, atol=1e-9)
    assert np.abs(want).max() > 0
    off = BeamTracker(env, ExpertConfig(**SMALL, velocity_ff=0.0))
    off.track(0, seconds=0.3)
    assert not off._feedforward(row).any()


def test_a_pruned_lookahead_simulates_fewer_samples_and_still_tracks(track) -> None:
    """``lookahead_share`` continues only the samples with the lowest segment-end cost
    through the lookahead (never fewer than ``beam``): its batch is that small, every sample
    it drops has no cost and so never joins the beam, and the clip is still tracked."""
    env, _ = track
    full = BeamTracker(env, ExpertConfig(**SMALL, lookahead_share=1.0)).track(0, seconds=1.0)
    pruned = BeamTracker(env, ExpertConfig(**SMALL))  # the default: a quarter
    assert pruned.look_sim.num_envs == 12 and pruned.sim.num_envs == 48
    stepped = []
    step = pruned.look_sim.step
    pruned.look_sim.step = lambda a: stepped.append(len(a)) or step(a)
    scored = []
    segment = pruned._segment
    pruned._segment = lambda *a: scored.append(segment(*a)) or scored[-1]
    tr = pruned.track(0, seconds=1.0)
    assert stepped and set(stepped) == {12}
    looked = [int(np.isfinite(s["cost"]).sum()) for s in scored]
    assert looked[-1] > 12  # the clip's last segment has nothing to look ahead to
    assert max(looked[:-1]) <= 12 and min(looked) >= SMALL["beam"], looked
    assert all(np.isfinite(s["cost"][s["order"]]).all() for s in scored)
    m = tr.metrics()
    assert m["success_clip"] and m["g_mpjpe_mm"] < 120, m
    assert abs(m["mpjpe_mm"] - full.metrics()["mpjpe_mm"]) < 40
    at_least_beam = BeamTracker(env, ExpertConfig(**SMALL, lookahead_share=0.01))
    assert at_least_beam.look_sim.num_envs == SMALL["beam"]
    plain = BeamTracker(env, ExpertConfig(**SMALL, lookahead_share=1.0))
    assert plain.look_sim is plain.sim  # every sample looks ahead
