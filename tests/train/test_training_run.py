"""Tiny real training runs: PPO on the human env for a few iterations, through the CLI and the
Trainer: finite losses, exact resume, seeded determinism, Ctrl-C, eval and play on the result."""

from __future__ import annotations

import csv
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import torch
from helpers import REPO, TINY, assert_state_equal

from retarget.cli.main import main
from retarget.recipe import load
from retarget.registry.loader import load_plugins
from retarget.train.checkpoint import load_checkpoint
from retarget.train.run_dir import latest_checkpoint, new_run_dir
from retarget.train.runner import Budget, Trainer

SAMPLES = 4 * 8  # num_envs x rollout_steps: env steps per iteration
TIMING = ("seconds", "_per_s", "elapsed_s")


@pytest.fixture(scope="module")
def recipe(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("recipe") / "tiny.yaml"
    path.write_text(TINY)
    return path


def rows(run: Path) -> list[dict[str, str]]:
    with (run / "metrics.csv").open() as f:
        return list(csv.DictReader(f))


def learning_columns(row: dict[str, str]) -> dict[str, str]:
    """A metrics row without its wall-clock columns (those differ between identical runs)."""
    return {k: v for k, v in row.items() if v and not any(t in k for t in TIMING)}


def trainer(recipe: Path, root: Path, name: str, threads: int | None = None) -> Trainer:
    resolved = load(str(recipe), load_plugins(), shorthands={}, assignments=[])
    return Trainer(
        resolved, new_run_dir(root, name), threads=threads, checkpoint_every=2, tensorboard=False
    )


def test_cli_run_has_finite_losses_checkpoints_and_eval_and_play(
    recipe: Path, tmp_path: Path
) -> None:
    rc = main(
        ["train", str(recipe), "--steps", str(4 * SAMPLES), "--runs-dir", str(tmp_path),
         "--checkpoint-every", "2", "--no-tensorboard"]
    )  # fmt: skip
    assert rc == 0
    run = (tmp_path / "tiny" / "latest").resolve()
    table = rows(run)
    assert len(table) == 4
    for row in table:
        for key in ("policy_loss", "value_loss", "approx_kl", "mean_reward"):
            assert math.isfinite(float(row[key])), (key, row)
    names = sorted(p.name for p in (run / "checkpoints").glob("ckpt-*.pt"))
    assert names == ["ckpt-0000002.pt", "ckpt-0000004.pt"]
    state = load_checkpoint(run / "checkpoints" / names[-1])
    assert state["progress"]["env_steps"] == 4 * SAMPLES

    report = tmp_path / "eval.json"
    rc = main(
        ["eval", str(run), "--every", "90", "--max-seconds", "1", "--num-envs", "4",
         "--json", str(report)]
    )  # fmt: skip
    assert rc == 0
    import json

    data = json.loads(report.read_text())
    overall = data["overall"]
    assert overall["runs"] >= 1
    assert 0.0 <= overall["success_frame"] <= 1.0
    assert math.isfinite(overall["headset_cm"])
    assert 0.0 <= overall["phc_success"] <= 1.0 and overall["phc_g_mpjpe_mm"] > 0

    # PHC's protocol: one run per clip, first frame to last
    rc = main(["eval", str(run), "--protocol", "phc", "--num-envs", "4", "--json", str(report)])
    assert rc == 0
    phc = json.loads(report.read_text())
    assert phc["overall"]["runs"] == len(phc["clips"])
    assert all(clip["runs"] == 1 for clip in phc["clips"].values())

    video = tmp_path / "play.gif"
    rc = main(["play", str(run), "--out", str(video), "--seconds", "0.3", "--size", "96x72"])
    assert rc == 0
    assert video.stat().st_size > 1000


def test_resume_continues_bit_for_bit_and_seed_repeats(recipe: Path, tmp_path: Path) -> None:
    straight = trainer(recipe, tmp_path, "straight")
    straight.train(Budget(steps=4 * SAMPLES))

    first = trainer(recipe, tmp_path, "first-half")
    ckpt = first.train(Budget(steps=2 * SAMPLES))
    # the same seed gives the same first iterations (learning figures, not wall clock)
    assert [learning_columns(r) for r in rows(first.run)] == [
        learning_columns(r) for r in rows(straight.run)[:2]
    ]

    # resumed on more physics threads (`retarget train --resume RUN --threads 2`): same result
    resumed = trainer(recipe, tmp_path, "second-half", threads=2)
    assert resumed.env.sim.settings.threads == 2
    resumed.restore(ckpt)
    resumed.train(Budget(steps=4 * SAMPLES))
    assert resumed.progress.iteration == straight.progress.iteration == 4
    assert_state_equal(resumed.algorithm.state_dict(), straight.algorithm.state_dict(), "algorithm")
    assert_state_equal(resumed.env.state_dict(), straight.env.state_dict(), "env")
    assert [learning_columns(r) for r in rows(resumed.run)] == [
        learning_columns(r) for r in rows(straight.run)[2:]
    ]


def test_ctrl_c_leaves_a_loadable_checkpoint_that_resumes(recipe: Path, tmp_path: Path) -> None:
    env = {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "osmesa")}
    cmd = [sys.executable, "-c", "from retarget.cli.main import main; raise SystemExit(main())"]
    proc = subprocess.Popen(
        [*cmd, "train", str(recipe), "--runs-dir", str(tmp_path), "--no-tensorboard",
         "--checkpoint-every", "1000"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=env, text=True,
    )  # fmt: skip
    metrics = tmp_path / "tiny" / "latest" / "metrics.csv"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        if metrics.exists() and len(metrics.read_text().splitlines()) >= 3:
            break
        time.sleep(0.2)
    assert proc.poll() is None, proc.communicate()[0]
    proc.send_signal(signal.SIGINT)
    output, _ = proc.communicate(timeout=120)
    assert proc.returncode == 130, output
    assert "interrupted" in output and "stopping after this iteration" in output
    run = (tmp_path / "tiny" / "latest").resolve()
    state = load_checkpoint(latest_checkpoint(run))
    done = state["progress"]["iteration"]
    assert done >= 2
    resumed = subprocess.run(
        [*cmd, "train", "--resume", str(run), "--steps", str(SAMPLES), "--no-tensorboard"],
        capture_output=True, text=True, env=env, timeout=120,
    )  # fmt: skip
    assert resumed.returncode == 0, resumed.stdout + resumed.stderr
    assert load_checkpoint(latest_checkpoint(run))["progress"]["iteration"] == done + 1


def test_export_onnx_matches_torch(recipe: Path, tmp_path: Path) -> None:
    ort = pytest.importorskip("onnxruntime")
    import json

    from retarget.train.load import load_run

    assert main(["train", str(recipe), "--steps", str(2 * SAMPLES), "--runs-dir", str(tmp_path),
                 "--no-tensorboard", "--set", "sim.actuation=pd"]) == 0  # fmt: skip
    run = tmp_path / "tiny" / "latest"
    assert main(["export", str(run), "--onnx"]) == 0
    onnx_path = run / "export" / "policy.onnx"
    meta = json.loads(onnx_path.with_suffix(".json").read_text())
    loaded = load_run(run, load_plugins(), num_envs=4)
    assert meta["obs_dim"] == loaded.env.obs_dims["actor"]
    assert meta["action_dim"] == loaded.env.action_dim == len(meta["torque_limits"])
    assert sum(s["size"] for s in meta["observation_sources"]) == meta["obs_dim"]
    # what an action means travels with the file: PD gains from the same torque limits
    assert meta["actuation"]["mode"] == "pd"
    np.testing.assert_allclose(meta["actuation"]["kp"], np.array(meta["torque_limits"]) / 0.5)
    np.testing.assert_allclose(meta["actuation"]["kd"], 0.1 * np.array(meta["actuation"]["kp"]))

    # real observations of the env (plus far-out ones that hit the normaliser's clip)
    obs = loaded.env.reset()["actor"].float()
    g = torch.Generator().manual_seed(0)
    wild = obs + 50.0 * torch.randn(obs.shape, generator=g)
    batch = torch.cat([obs, wild])
    expected = loaded.algorithm.act({"actor": batch}).numpy()
    session = ort.InferenceSession(str(onnx_path))
    (got,) = session.run(None, {"obs": batch.numpy()})
    assert got.shape == expected.shape
    np.testing.assert_allclose(got, expected, atol=1e-5, rtol=0)
    assert np.abs(expected).max() > 1e-3  # a policy that outputs something


def test_export_needs_a_format(recipe: Path, tmp_path: Path, capsys) -> None:
    assert main(["train", str(recipe), "--steps", str(SAMPLES), "--runs-dir", str(tmp_path),
                 "--no-tensorboard"]) == 0  # fmt: skip
    assert main(["export", str(tmp_path / "tiny" / "latest")]) == 2
    assert "--onnx" in capsys.readouterr().err


def test_logs_reward_terms_terminations_and_resume_drops_redone_rows(
    recipe: Path, tmp_path: Path
) -> None:
    first = trainer(recipe, tmp_path, "logs")
    first.train(Budget(steps=6 * SAMPLES))
    table = rows(first.run)
    columns = set(table[0]) | set(table[-1])
    assert {"episode_joint_pos", "episode_link_pos", "episode_action_diff"} <= columns
    shares = [k for k in columns if k.startswith("end_")]
    assert {"end_fall", "end_episode_cap"} <= set(shares)
    for row in table:
        values = [float(row[k]) for k in shares if row.get(k)]
        if values:
            assert abs(sum(values) - 1.0) < 1e-6

    # resuming from iteration 2 (written by checkpoint_every=2) redoes 3..6: once each in the CSV
    again = Trainer(first.resolved, first.run, checkpoint_every=2, tensorboard=False)
    again.restore(first.run / "checkpoints" / "ckpt-0000002.pt")
    assert [float(r["iteration"]) for r in rows(first.run)] == [1.0, 2.0]
    again.train(Budget(steps=4 * SAMPLES))
    assert [float(r["iteration"]) for r in rows(first.run)] == [1.0, 2.0, 3.0, 4.0]


def test_play_from_the_shipped_device_recording(recipe: Path, tmp_path: Path) -> None:
    """examples/recordings/walk_openxr.jsonl (OpenXR convention, a headset clock, a dropout)
    drives a trained run, and is exactly what its generator script writes."""
    import importlib.util

    from retarget.motion.device_recording import write_recording

    path = REPO / "examples" / "recordings" / "walk_openxr.jsonl"
    spec = importlib.util.spec_from_file_location("make_sample", path.with_name("make_sample.py"))
    maker = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(maker)
    again = write_recording(tmp_path / "again.jsonl", maker.sample(), convention="openxr")
    assert again.read_text() == path.read_text(), "regenerate: python " + str(spec.origin)
    assert main(["train", str(recipe), "--steps", str(SAMPLES), "--runs-dir", str(tmp_path),
                 "--no-tensorboard"]) == 0  # fmt: skip
    video = tmp_path / "rec.gif"
    rc = main(["play", str(tmp_path / "tiny" / "latest"), "--input", str(path),
               "--out", str(video), "--size", "96x72", "--seconds", "1"])  # fmt: skip
    assert rc == 0
    assert video.stat().st_size > 1000
    # --input and --motions together is a user error
    assert main(["play", str(tmp_path / "tiny" / "latest"), "--input", str(path),
                 "--motions", str(path), "--out", str(video)]) == 2  # fmt: skip


def test_the_main_command_runs_out_of_the_box(tmp_path: Path) -> None:
    """`retarget train --character dino --sensors hmd` on the packaged recipe and the generated
    motions (made small: fewer envs and a short rollout)."""
    rc = main(["train", "--character", "dino", "--sensors", "hmd", "--steps", "1",
               "--num-envs", "8", "--set", "algorithm.rollout_steps=4", "--runs-dir",
               str(tmp_path), "--no-tensorboard"])  # fmt: skip
    assert rc == 0
    run = (tmp_path / "dino-hmd" / "latest").resolve()
    (row,) = rows(run)
    assert float(row["step"]) == 8 * 4
    assert math.isfinite(float(row["policy_loss"]))
    lock = (run / "recipe.lock.yaml").read_text()
    assert "type: dino" in lock and "type: hmd" in lock and "type: ppo" in lock


def test_a_run_plays_in_another_scene_and_refuses_other_observations(
    recipe: Path, tmp_path: Path, capsys
) -> None:
    from retarget.train.load import load_run

    assert main(["train", str(recipe), "--steps", str(SAMPLES), "--runs-dir", str(tmp_path),
                 "--no-tensorboard"]) == 0  # fmt: skip
    run = tmp_path / "tiny" / "latest"
    loaded = load_run(run, load_plugins(), scene="chair", assignments=["scene.position=[2,0]"])
    assert loaded.resolved.component("scene").entry.name == "chair"
    model = loaded.env.sim.model
    chair = [model.body(i).name for i in range(model.nbody) if "chair" in model.body(i).name]
    assert chair, "the chair's bodies are in the compiled model"
    video = tmp_path / "chair.png"
    assert main(["play", str(run), "--scene", "chair", "--set", "scene.position=[1,0]",
                 "--out", str(video), "--seconds", "0.3", "--size", "96x72",
                 "--azimuth", "90", "--elevation", "-5"]) == 0  # fmt: skip
    assert video.stat().st_size > 1000

    # a height map the policy never saw changes the observation: refused, naming the flag
    rc = main(["eval", str(run), "--set", "observers=[height_map]", "--every", "90",
               "--max-seconds", "0.5", "--num-envs", "2"])  # fmt: skip
    assert rc != 0
    err = capsys.readouterr().err
    assert "does not fit" in err and "--set observers=[height_map]" in err


def test_ctrl_c_pressed_during_the_final_checkpoint_does_not_lose_it(
    recipe: Path, tmp_path: Path
) -> None:
    t = trainer(recipe, tmp_path, "impatient")
    save = t.save
    pressed = []

    def save_while_pressed() -> Path:
        if t._stop_requests:  # the final checkpoint: the user presses Ctrl-C twice more
            for _ in range(2):
                os.kill(os.getpid(), signal.SIGINT)
                pressed.append(1)
        return save()

    t.save = save_while_pressed  # type: ignore[method-assign]
    t._request_stop(signal.SIGINT, None)  # the first Ctrl-C: stop after this iteration
    last = t.train(Budget(steps=10 * SAMPLES))
    assert pressed and last.exists()
    assert load_checkpoint(last)["progress"]["iteration"] == t.progress.iteration == 1


def test_a_killed_run_resumes_losing_at_most_one_interval(recipe: Path, tmp_path: Path) -> None:
    """SIGKILL (no handler runs) while training: the last checkpoint loads, the run lock is
    free again, and --resume continues from it."""
    env = {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "osmesa")}
    cmd = [sys.executable, "-c", "from retarget.cli.main import main; raise SystemExit(main())"]
    proc = subprocess.Popen(
        [*cmd, "train", str(recipe), "--runs-dir", str(tmp_path), "--no-tensorboard",
         "--checkpoint-every", "1"],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env,
    )  # fmt: skip
    ckpts = tmp_path / "tiny" / "latest" / "checkpoints"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and len(list(ckpts.glob("ckpt-*.pt"))) < 3:
        time.sleep(0.05)
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=30)
    run = (tmp_path / "tiny" / "latest").resolve()
    last = load_checkpoint(latest_checkpoint(run))["progress"]["iteration"]
    assert last >= 3
    metrics_rows = len((run / "metrics.csv").read_text().splitlines()) - 1
    assert metrics_rows - last <= 1  # at most the iteration after the last checkpoint is lost
    resumed = subprocess.run(
        [*cmd, "train", "--resume", str(run), "--steps", str(SAMPLES)],
        capture_output=True, text=True, env=env, timeout=120,
    )  # fmt: skip
    assert resumed.returncode == 0, resumed.stdout + resumed.stderr
    assert load_checkpoint(latest_checkpoint(run))["progress"]["iteration"] == last + 1


def test_a_trainer_given_sizes_locks_them_so_the_run_resumes(recipe: Path, tmp_path: Path) -> None:
    """Trainer(num_envs=, threads=) builds the env with them and the lock says so: resuming
    the run from the command line builds the same env (it failed on the state's env count)."""
    resolved = load(str(recipe), load_plugins(), shorthands={}, assignments=[])
    run = new_run_dir(tmp_path / "runs", "sized")
    t = Trainer(resolved, run, num_envs=3, threads=1, checkpoint_every=1, tensorboard=False)
    assert t.env.num_envs == 3
    t.train(Budget(steps=2 * 3 * 8))
    lock = (run / "recipe.lock.yaml").read_text()
    assert "num_envs: 3" in lock
    assert main(["train", "--resume", str(run), "--steps", "24", "--no-tensorboard"]) == 0


def test_a_budget_ending_on_a_checkpoint_iteration_writes_it_once(
    recipe: Path, tmp_path: Path
) -> None:
    t = trainer(recipe, tmp_path, "once")  # checkpoint_every=2
    written = []
    save = t.save

    def counting():
        written.append(t.progress.iteration)
        return save()

    t.save = counting  # type: ignore[method-assign]
    t.train(Budget(steps=4 * SAMPLES))
    assert written == [2, 4]
    t.train(Budget(steps=5 * SAMPLES))  # ends between checkpoints: the end is saved
    assert written == [2, 4, 5]
