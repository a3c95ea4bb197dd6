"""CLI shorthands reach the run through the recipe (the lock file is exactly what ran), and the
recipe's motion format is the one that reads the clips."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml
from helpers import TINY

from retarget.cli.main import main
from retarget.env.build import motion_formats
from retarget.errors import MotionError
from retarget.motion.sources import load_motions
from retarget.plugins.formats.bvh import Bvh
from retarget.recipe import parse_text, resolve
from retarget.registry.loader import load_plugins
from retarget.train.checkpoint import load_checkpoint
from retarget.train.run_dir import latest_checkpoint


def test_num_envs_and_threads_flags_are_locked_and_the_run_resumes(
    tmp_path: Path, capsys
) -> None:
    recipe = tmp_path / "tiny.yaml"
    recipe.write_text(TINY)
    assert main(["train", str(recipe), "--num-envs", "2", "--threads", "1", "--steps", "16",
                 "--runs-dir", str(tmp_path), "--no-tensorboard"]) == 0  # fmt: skip
    run = tmp_path / "tiny" / "latest"
    lock = yaml.safe_load((run / "recipe.lock.yaml").read_text())
    assert lock["env"]["num_envs"] == 2 and lock["sim"]["threads"] == 1
    assert main(["train", "--resume", str(run), "--steps", "16", "--no-tensorboard"]) == 0
    assert "resumed" in capsys.readouterr().out
    assert main(["train", "--resume", str(run), "--threads", "2", "--steps", "16",
                 "--no-tensorboard"]) == 0  # fmt: skip
    assert yaml.safe_load((run / "recipe.lock.yaml").read_text())["sim"]["threads"] == 2
    assert main(["train", "--resume", str(run), "--num-envs", "4", "--steps", "64"]) != 0
    assert "environment count" in capsys.readouterr().err


def test_the_recipes_motion_format_reads_with_its_own_settings(tmp_path: Path) -> None:
    sample = Bvh.write_sample(tmp_path)
    registry = load_plugins()

    def formats(units: str):
        text = TINY + f"motions: {{path: {sample}, format: {{type: bvh, units: {units}}}}}\n"
        return motion_formats(resolve(parse_text(text, "r.yaml", ".yaml"), registry), registry)

    mm, cm = formats("mm"), formats("cm")
    assert mm is not None and mm["bvh"].config.units == "mm"
    assert load_motions(sample, cm)[0].height > 1.0  # the sample is in centimetres
    with pytest.raises(MotionError, match="wrong units"):  # read as mm: a 17 cm person
        load_motions(sample, mm)
    default = motion_formats(resolve(parse_text(TINY, "r.yaml", ".yaml"), registry), registry)
    assert default is not None and "bvh" in default


def test_env_reads_clips_with_the_recipes_format(tmp_path: Path, monkeypatch) -> None:
    from retarget.env.build import env_from_recipe

    sample = Bvh.write_sample(tmp_path)
    seen: list[str | None] = []
    original = Bvh.read

    def read(self, path):
        seen.append(self.config.units)
        return original(self, path)

    monkeypatch.setattr(Bvh, "read", read)
    monkeypatch.setenv("RETARGET_CACHE", "off")  # the reader itself, not a cached clip
    registry = load_plugins()
    text = TINY + f"motions: {{path: {sample}, format: {{type: bvh, units: cm}}}}\n"
    env_from_recipe(resolve(parse_text(text, "r.yaml", ".yaml"), registry), registry=registry)
    assert seen == ["cm"]


def test_training_that_goes_non_finite_stops_naming_the_iteration(
    tmp_path: Path, monkeypatch, capsys
) -> None:
    from retarget.plugins.algorithms.ppo import PPO

    recipe = tmp_path / "tiny.yaml"
    recipe.write_text(TINY)
    original = PPO.train_iteration
    calls = []

    def train_iteration(self, env):
        stats = dict(original(self, env).stats)
        calls.append(1)
        if len(calls) == 3:
            stats["policy_loss"] = float("nan")
        return stats  # a plain dict of statistics is still accepted

    monkeypatch.setattr(PPO, "train_iteration", train_iteration)
    rc = main(["train", str(recipe), "--steps", "320", "--checkpoint-every", "1",
               "--runs-dir", str(tmp_path), "--no-tensorboard"])  # fmt: skip
    err = capsys.readouterr().err
    assert rc == 2 and "iteration 3" in err and "policy_loss" in err
    names = sorted(p.name for p in (tmp_path / "tiny" / "latest" / "checkpoints").iterdir())
    assert names == ["ckpt-0000001.pt", "ckpt-0000002.pt"], "no checkpoint of the NaN state"


def test_a_run_being_trained_cannot_be_resumed_by_a_second_process(tmp_path: Path) -> None:
    import subprocess
    import sys

    from retarget.errors import RetargetError
    from retarget.train.run_dir import RunLock, new_run_dir

    run = new_run_dir(tmp_path, "busy")
    holder = subprocess.Popen(
        [sys.executable, "-c",
         "import sys, time; from pathlib import Path; from retarget.train.run_dir import RunLock;"
         f"lock = RunLock(Path({str(run)!r})).acquire(); print('held', flush=True);"
         "time.sleep(30)"],
        stdout=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        assert holder.stdout is not None and holder.stdout.readline().strip() == "held"
        try:
            RunLock(run).acquire()
        except RetargetError as exc:
            assert "being trained by pid" in str(exc)
        else:
            raise AssertionError("a second writer got the lock")
    finally:
        holder.kill()
        holder.wait()
    RunLock(run).acquire().release()  # the lock died with its process (even on SIGKILL)
    assert new_run_dir(tmp_path, "busy") != run  # two runs started at once never share


def test_a_failed_start_leaves_no_run_and_keeps_latest(tmp_path: Path, capsys) -> None:
    recipe = tmp_path / "tiny.yaml"
    recipe.write_text(TINY)
    assert main(["train", str(recipe), "--steps", "16", "--runs-dir", str(tmp_path),
                 "--no-tensorboard"]) == 0  # fmt: skip
    before = (tmp_path / "tiny" / "latest").resolve()
    runs = sorted((tmp_path / "tiny").iterdir())
    broken = tmp_path / "broken.bvh"
    broken.write_text("HIERARCHY\nnot a skeleton\n")
    assert main(["train", str(recipe), "--motions", str(broken), "--steps", "16",
                 "--runs-dir", str(tmp_path), "--no-tensorboard"]) == 2  # fmt: skip
    assert "broken.bvh" in capsys.readouterr().err
    assert (tmp_path / "tiny" / "latest").resolve() == before
    assert sorted((tmp_path / "tiny").iterdir()) == runs
    assert main(["train", str(recipe), "--motions", str(broken), "--steps", "16",
                 "--runs-dir", str(tmp_path / "fresh"), "--no-tensorboard"]) == 2  # fmt: skip
    assert not (tmp_path / "fresh" / "tiny").exists()


def test_resume_keeps_the_runs_settings_and_its_budget_is_more(tmp_path: Path) -> None:
    recipe = tmp_path / "tiny.yaml"
    recipe.write_text(TINY)
    assert main(["train", str(recipe), "--num-envs", "2", "--steps", "32", "--runs-dir",
                 str(tmp_path), "--checkpoint-every", "1", "--no-tensorboard"]) == 0  # fmt: skip
    run = (tmp_path / "tiny" / "latest").resolve()
    settings = json.loads((run / "train_settings.json").read_text())
    assert settings == {"checkpoint_every": 1, "tensorboard": False}
    before = latest_checkpoint(run)
    first = load_checkpoint(before)["progress"]
    assert main(["train", "--resume", str(run), "--steps", "32"]) == 0  # no flags repeated
    after = load_checkpoint(latest_checkpoint(run))["progress"]
    assert after["env_steps"] >= first["env_steps"] + 32  # "more", not "in total"
    ckpts = sorted((run / "checkpoints").glob("ckpt-*.pt"))
    assert len(ckpts) == after["iteration"]  # one per iteration, as recorded
    assert not (run / "tensorboard").exists()


def test_a_shipped_models_lock_needs_its_motions_given(
    tmp_path: Path, capsys, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A shipped lock holds out a style by pattern but carries no motion path: training from
    it must not fall back to the generated clips unnoticed; with --motions it starts."""
    from retarget.motion.sources import ENV_VAR

    monkeypatch.delenv(ENV_VAR, raising=False)
    recipe = tmp_path / "tiny.yaml"
    recipe.write_text(TINY)
    args = ["train", str(recipe), "--set", "motions.exclude=['*_normal_*']", "--steps", "16",
            "--runs-dir", str(tmp_path), "--no-tensorboard"]  # fmt: skip
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "motions.path" in err and "--motions" in err and "*_normal_*" in err
    assert not (tmp_path / "tiny").exists()  # no run directory left behind
    clips = tmp_path / "clips"
    clips.mkdir()
    from retarget.motion.bvh_write import write_bvh
    from retarget.motion.procedural import default_motions

    write_bvh(default_motions()[1], clips / "walk_active_001.bvh")
    assert main([*args, "--motions", str(clips)]) == 0
