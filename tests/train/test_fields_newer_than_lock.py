"""Training from a run's lock recorded before a field existed says which of today's defaults
the new run takes in its place, unless the user set that field."""

from __future__ import annotations

from pathlib import Path

from retarget import pretrained
from retarget.recipe import load
from retarget.registry.loader import load_plugins
from retarget.train.start import fields_newer_than_lock

REGISTRY = load_plugins(strict=True)


def test_a_lock_before_hinged_elbows_is_named_until_the_field_is_set() -> None:
    lock = pretrained.model_dir("dino-hmd-teacher") / "recipe.lock.yaml"
    assert "hinge_elbows" not in lock.read_text()
    resolved = load(lock, REGISTRY)
    notes = fields_newer_than_lock(lock, resolved)
    assert len(notes) == 1 and "env.hinge_elbows" in notes[0] and str(lock) in notes[0]
    assert "--set env.hinge_elbows=false" in notes[0]
    kept = ["env.hinge_elbows=false"]
    assert fields_newer_than_lock(lock, load(lock, REGISTRY, assignments=kept)) == []


def test_a_plain_recipe_or_a_packaged_name_gives_no_note(tmp_path: Path) -> None:
    plain = tmp_path / "mine.yaml"
    plain.write_text("env: {num_envs: 4}\n")
    assert fields_newer_than_lock(plain, load(plain, REGISTRY)) == []
    assert fields_newer_than_lock("dino_teacher", load(None, REGISTRY)) == []
    assert fields_newer_than_lock(None, load(None, REGISTRY)) == []
