"""Pretrained models: a trained run packaged as a shipped model (lock, policy-only checkpoint,
card) works as ``pretrained:NAME`` in eval, play, export and as a DAgger teacher, writes its
outputs outside the package; and every model the package ships loads and acts."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import torch
import yaml
from helpers import REPO, TINY_TEACHER

import retarget.pretrained as pretrained
from retarget.cli.main import main
from retarget.errors import RetargetError
from retarget.kinds.capabilities import PoseEstimating
from retarget.pretrained import ModelCard
from retarget.registry.loader import load_plugins
from retarget.train.load import load_run, locked_recipe, prepared_recipe
from retarget.train.package_model import package

SHIPPED = pretrained.names()


def _card(name: str, **changes) -> ModelCard:
    fields = dict(name=name, summary="a tiny teacher", character="human",
                  sensors=["full_body", "reference_action"], algorithm="ppo",
                  data="the generated default clips", licence="none (generated data)",
                  env_steps=64, cpu_hours=0.001)  # fmt: skip
    return ModelCard(**{**fields, **changes})


@pytest.fixture(scope="module")
def models(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A tiny teacher trained for real, then packaged into a models folder of its own."""
    import os

    root = tmp_path_factory.mktemp("pretrained")
    here = os.getcwd()
    os.chdir(root)
    try:
        (root / "teacher.yaml").write_text(TINY_TEACHER)
        assert main(["train", "teacher.yaml", "--steps", "64", "--no-tensorboard"]) == 0
        models = root / "models"
        package(root / "runs" / "teacher" / "latest", _card("tiny-teacher"), models=models)
    finally:
        os.chdir(here)
    return models


@pytest.fixture
def shipped(models: Path, monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> Path:
    monkeypatch.setattr(pretrained, "MODELS", models)
    monkeypatch.chdir(tmp_path)
    return models


def test_a_packaged_run_is_small_and_listed(shipped: Path, capsys) -> None:
    folder = shipped / "tiny-teacher"
    names = sorted(p.name for p in folder.rglob("*") if p.is_file())
    assert names == ["CURRENT", "MODEL_CARD.md", "card.json", "ckpt-0000002.pt", "recipe.lock.yaml"]
    assert main(["pretrained"]) == 0 and "tiny-teacher" in capsys.readouterr().out
    assert main(["pretrained", "path", "tiny-teacher"]) == 0
    assert Path(capsys.readouterr().out.strip()) == folder
    assert main(["pretrained", "show", "tiny-teacher"]) == 0
    assert "the generated default clips" in capsys.readouterr().out
    lock = (folder / "recipe.lock.yaml").read_text()
    assert "path: null" in lock  # the training data is named in the card, never needed


def test_an_unknown_name_suggests_the_close_one(shipped: Path) -> None:
    with pytest.raises(RetargetError, match="did you mean 'tiny-teacher'"):
        pretrained.model_dir("tiny-teachr")
    assert main(["eval", "pretrained:nope"]) != 0


def test_eval_play_and_export_take_a_pretrained_name(shipped: Path, tmp_path: Path) -> None:
    before = sorted(p.name for p in (shipped / "tiny-teacher").rglob("*"))
    assert main(["eval", "pretrained:tiny-teacher", "--every", "200", "--max-seconds", "0.5",
                 "--num-envs", "2"]) == 0  # fmt: skip
    report = json.loads((tmp_path / "eval-tiny-teacher.json").read_text())
    assert report["overall"]["runs"] >= 1
    assert main(["play", "pretrained:tiny-teacher", "--seconds", "0.3", "--out",
                 str(tmp_path / "p.gif")]) == 0  # fmt: skip
    assert (tmp_path / "p.gif").stat().st_size > 1000
    assert main(["export", "pretrained:tiny-teacher", "--onnx"]) == 0
    assert (tmp_path / "export" / "tiny-teacher" / "policy.onnx").is_file()
    assert sorted(p.name for p in (shipped / "tiny-teacher").rglob("*")) == before


def test_a_pretrained_teacher_distils_a_student(shipped: Path, tmp_path: Path) -> None:
    assert main(["train", "--sensors", "three_point", "--teacher", "pretrained:tiny-teacher",
                 "--steps", "64", "--set", "env.num_envs=4", "--set",
                 "algorithm.rollout_steps=8", "--set", "algorithm.actor_hidden=[32]",
                 "--no-tensorboard", "--set", "name=student"]) == 0  # fmt: skip
    lock = (tmp_path / "runs" / "student" / "latest" / "recipe.lock.yaml").read_text()
    assert "teacher: pretrained:tiny-teacher" in lock  # portable: the name, not a path


def test_a_policy_only_checkpoint_acts_like_the_full_one(shipped: Path, models: Path) -> None:
    registry = load_plugins()
    full = load_run(models.parent / "runs" / "teacher" / "latest", registry)
    slim = load_run("pretrained:tiny-teacher", registry)
    obs = full.env.reset()
    assert torch.equal(full.algorithm.act(obs), slim.algorithm.act(obs))


@pytest.mark.parametrize("name", SHIPPED)
def test_every_shipped_model_loads_and_acts(name: str) -> None:
    card = pretrained.card(name)
    assert card.licence and card.data and card.env_steps > 0 and card.cpu_hours > 0
    loaded = load_run(f"pretrained:{name}", load_plugins(), num_envs=2)
    assert loaded.resolved.recipe.character.type == card.character
    if isinstance(loaded.algorithm, PoseEstimating):  # it estimates the body, it does not act
        estimator = loaded.algorithm.pose_estimator()
        out, _ = estimator.estimate_rows(torch.arange(0, loaded.env.library.num_frames, 17))
        assert torch.isfinite(out.root_pos).all() and torch.isfinite(out.rot6d).all()
        return
    obs = loaded.env.reset()
    for _ in range(5):
        obs, *_ = loaded.env.step(loaded.algorithm.act(obs))
    assert all(torch.isfinite(v).all() for v in obs.values())
    size = sum(f.stat().st_size for f in pretrained.model_dir(name).rglob("*") if f.is_file())
    assert size < 5e6


def _locked_algorithm(name: str) -> dict:
    lock = pretrained.model_dir(name) / "recipe.lock.yaml"
    return yaml.safe_load(lock.read_text(encoding="utf-8")).get("algorithm") or {}


STUDENTS = [n for n in SHIPPED if "teacher" in _locked_algorithm(n)]


@pytest.mark.parametrize("name", STUDENTS)
def test_every_shipped_student_names_a_shipped_teacher_it_can_distil_from(name: str) -> None:
    """The student's lock can be trained on (resume, --init-from): its teacher is a shipped
    model holding the checkpoint it names, configured as the student read it."""
    registry = load_plugins()
    resolved, _ = locked_recipe(pretrained.model_dir(name), registry)
    algorithm = resolved.to_dict()["algorithm"]
    assert pretrained.is_pretrained(algorithm["teacher"])
    assert pretrained.card(name).teacher == algorithm["teacher"]  # the card says the same
    teacher = pretrained.resolve(algorithm["teacher"])
    if algorithm.get("teacher_checkpoint"):
        assert (teacher / algorithm["teacher_checkpoint"]).is_file()
    prepared = prepared_recipe(resolved, registry)  # raises on a sensor set up otherwise
    assert prepared.to_dict() == resolved.to_dict()  # nothing to change: it is as trained


def test_the_package_ships_every_model_file() -> None:
    text = (REPO / "pyproject.toml").read_text()
    for pattern in ("models/*/card.json", "models/*/recipe.lock.yaml", "models/*/checkpoints/*.pt",
                    "models/*/checkpoints/CURRENT"):  # which checkpoint a model acts with
        assert pattern in text


README_EXAMPLE = "human-three_point-student"


@pytest.mark.skipif(README_EXAMPLE not in SHIPPED, reason="the README's student is not shipped")
def test_the_readme_first_example_plays_the_shipped_student(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """README's first command, with a shorter clip: the shipped student driven by the sample
    headset recording, and how closely its head followed the headset."""
    out = tmp_path / "me.gif"
    rc = main(["play", f"pretrained:{README_EXAMPLE}", "--input",
               str(REPO / "examples" / "recordings" / "walk_openxr.jsonl"), "--seconds", "1",
               "--out", str(out)])  # fmt: skip
    assert rc == 0 and out.stat().st_size > 1000
    said = capsys.readouterr().out
    assert "head to headset" in said and " over 1.0 s" in said, said
    assert f"pretrained:{README_EXAMPLE}" in (REPO / "README.md").read_text()


def test_follow_summary_names_when_the_headset_was_lost() -> None:
    from retarget.cli.play_cmd import follow_summary

    assert "followed to the end" in follow_summary([0.1, 0.2, 0.3], 36.0)
    lost = follow_summary([0.1] * 36 + [0.6, 0.2], 36.0)
    assert "lost it at 1.0 s" in lost and "60 cm max" in lost


def _lock_without(run: Path, section: str, field: str) -> Path:
    """A copy of a shipped model whose lock lacks ``section.field``, as locks written before
    the field existed do (whatever the shipped locks now say)."""
    import shutil

    import yaml

    shutil.copytree(pretrained.model_dir("human-teacher"), run)
    path = run / "recipe.lock.yaml"
    lock = yaml.safe_load(path.read_text())
    lock[section].pop(field, None)
    path.write_text(yaml.safe_dump(lock, sort_keys=False))
    return run


def test_a_run_locked_before_env_devices_keeps_the_performers_size(tmp_path: Path) -> None:
    """A lock without ``env.devices`` (written before the field) reads as ``person``, what its
    devices were when it trained; a new recipe without it gets ``character``."""
    import yaml

    from retarget.recipe import load
    from retarget.train.load import locked_recipe

    registry = load_plugins()
    run = _lock_without(tmp_path / "old", "env", "devices")
    assert locked_recipe(run, registry)[0].recipe.env.devices == "person"
    lock = yaml.safe_load((run / "recipe.lock.yaml").read_text())
    lock["env"]["devices"] = "character"
    (run / "recipe.lock.yaml").write_text(yaml.safe_dump(lock, sort_keys=False))
    assert locked_recipe(run, registry)[0].recipe.env.devices == "character"
    fresh = tmp_path / "fresh.yaml"
    fresh.write_text("extends: null\ncharacter: human\nsensors: [three_point]\n")
    assert load(str(fresh), registry).recipe.env.devices == "character"


@pytest.mark.parametrize(
    ("section", "field"),
    [("motions", "level_feet"),  # trained on the file's foot tilt; a new recipe levels feet
     ("env", "hinge_elbows")],  # its elbows bent by the angle alone; a new recipe hinges them
)  # fmt: skip
def test_a_run_locked_before_a_switch_keeps_what_it_trained_on(
    tmp_path: Path, section: str, field: str
) -> None:
    """A lock without a later on-by-default switch reads as ``false``, what its references
    were when it trained; a new recipe without it gets ``true``."""
    from retarget.recipe import load
    from retarget.train.load import locked_recipe

    registry = load_plugins()
    run = _lock_without(tmp_path / "old", section, field)
    old = locked_recipe(run, registry)[0].recipe
    assert getattr(getattr(old, section), field) is False
    fresh = tmp_path / "fresh.yaml"
    fresh.write_text("extends: null\ncharacter: human\nsensors: [three_point]\n")
    assert getattr(getattr(load(str(fresh), registry).recipe, section), field) is True
