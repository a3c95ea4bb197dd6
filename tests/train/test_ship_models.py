"""``benchmarks/ship_models.py``'s kept training state: README's flow resumes a kept state in
place and ships it again, so keeping it must not delete what it is copying."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parents[2] / "benchmarks"))

import ship_models

from retarget.errors import RetargetError


def _state(folder: Path, iterations: tuple[int, ...]) -> Path:
    (folder / "checkpoints").mkdir(parents=True)
    (folder / "recipe.lock.yaml").write_text("algorithm: {type: dagger, teacher: runs/t}\n")
    (folder / "metrics.csv").write_text("step,elapsed_s\n8192,10\n")
    (folder / "train_settings.json").write_text("{}")
    for i in iterations:
        (folder / "checkpoints" / f"ckpt-{i:07d}.pt").write_bytes(bytes([i % 256]) * 8)
    return folder


@pytest.fixture
def here(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setattr(ship_models, "HERE", tmp_path)
    return tmp_path


def test_a_state_resumed_in_place_keeps_its_files_and_its_newest_checkpoint(here: Path) -> None:
    kept = _state(here / "pretrain" / "m", (10, 20, 30))
    out = ship_models.keep_state(kept, "m", teacher="pretrained:t")
    assert out == kept
    assert [p.name for p in (out / "checkpoints").iterdir()] == ["ckpt-0000030.pt"]
    assert (out / "checkpoints" / "ckpt-0000030.pt").read_bytes() == bytes([30]) * 8
    assert (out / "metrics.csv").read_text().startswith("step")
    assert "pretrained:t" in (out / "recipe.lock.yaml").read_text()


def test_another_run_replaces_the_kept_state(here: Path) -> None:
    _state(here / "pretrain" / "m", (5,))
    run = _state(here / "runs" / "r", (40, 50))
    out = ship_models.keep_state(run, "m")
    assert sorted(p.name for p in (out / "checkpoints").iterdir()) == ["ckpt-0000050.pt"]
    assert "runs/t" in (out / "recipe.lock.yaml").read_text()
    assert len(list((run / "checkpoints").iterdir())) == 2  # the source is untouched


def test_a_students_teacher_checkpoint_is_found_for_keeping(tmp_path: Path) -> None:
    """Shipping a teacher again replaces its folder; the checkpoint a shipped student's lock
    names is read first so that it can be written back."""
    teacher = tmp_path / "t" / "checkpoints"
    teacher.mkdir(parents=True)
    (teacher / "ckpt-0000100.pt").write_bytes(b"old")
    (teacher / "ckpt-0000200.pt").write_bytes(b"new")
    (tmp_path / "t" / "recipe.lock.yaml").write_text("algorithm: {type: ppo}\n")
    for name, ckpt in (("s", "checkpoints/ckpt-0000100.pt"), ("u", "../../escape.pt")):
        (tmp_path / name).mkdir()
        (tmp_path / name / "recipe.lock.yaml").write_text(
            f"algorithm: {{type: dagger, teacher: 'pretrained:t', teacher_checkpoint: '{ckpt}'}}\n"
        )
    assert ship_models.students_checkpoints("t", tmp_path) == {"ckpt-0000100.pt": b"old"}
    assert ship_models.students_checkpoints("s", tmp_path) == {}


def test_a_shipped_teacher_is_its_new_checkpoint_beside_a_higher_numbered_kept_one(
    tmp_path: Path,
) -> None:
    """A teacher continued in a new run numbers its checkpoints from 1 again; the older file
    kept for its shipped students (ckpt 962) must not become the model (ckpt 362)."""
    import torch

    from retarget.pretrained import ModelCard
    from retarget.train.checkpoint import save_checkpoint
    from retarget.train.package_model import package
    from retarget.train.run_dir import CHECKPOINTS, CURRENT, latest_checkpoint

    run = tmp_path / "run"
    (run / CHECKPOINTS).mkdir(parents=True)
    (run / "recipe.lock.yaml").write_text("character: human\nalgorithm: {type: ppo}\n")
    save_checkpoint(run / CHECKPOINTS / "ckpt-0000362.pt",
                    {"algorithm": {"w": torch.ones(1)}, "progress": {}})  # fmt: skip
    card = ModelCard(name="t", summary="s", character="human", sensors=[], algorithm="ppo",
                     data="d", licence="l", env_steps=1, cpu_hours=0.1)  # fmt: skip
    out = package(run, card, models=tmp_path / "models")
    (out / CHECKPOINTS / "ckpt-0000962.pt").write_bytes(b"a student's teacher")
    assert latest_checkpoint(out).name == "ckpt-0000362.pt"
    (out / CHECKPOINTS / CURRENT).write_text("../../escape.pt")
    with pytest.raises(RetargetError, match="no checkpoint file"):
        latest_checkpoint(out)
    (out / CHECKPOINTS / CURRENT).unlink()
    assert latest_checkpoint(out).name == "ckpt-0000962.pt"  # a run without the marker


def test_a_student_whose_teacher_moved_to_another_recipe_is_named(tmp_path: Path) -> None:
    """A kept teacher checkpoint runs under the teacher's new lock: a student whose lock no
    longer prepares unchanged against it (here the headset student pointed at the teacher
    whose residual base reads two frames ahead) is reported, its own teacher is not."""
    import shutil

    import yaml

    from retarget import pretrained

    shipped = pretrained.model_dir("human-hmd-student")
    student = tmp_path / "s"
    student.mkdir()
    lock = yaml.safe_load((shipped / "recipe.lock.yaml").read_text())
    assert lock["algorithm"]["teacher"] == "pretrained:human-hmd-teacher"
    shutil.copy2(shipped / "recipe.lock.yaml", student / "recipe.lock.yaml")
    assert ship_models.students_left_behind("human-hmd-teacher", tmp_path) == []
    lock["algorithm"]["teacher"] = "pretrained:human-teacher"
    (student / "recipe.lock.yaml").write_text(yaml.safe_dump(lock, sort_keys=False))
    behind = ship_models.students_left_behind("human-teacher", tmp_path)
    assert len(behind) == 1 and behind[0].startswith("s: ") and "reference_action" in behind[0]
