"""Starting or resuming a training run from what a user asked for: the checks, the recipe
changes, the run's name and its recorded settings. The ``retarget train`` command only parses
flags and prints; everything that decides what the run is lives here, below the CLI, so a
script that trains through :class:`~retarget.train.runner.Trainer` starts runs the same way.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

from retarget.errors import RecipeError
from retarget.train.run_dir import LOCK, default_run_name

if TYPE_CHECKING:
    from retarget.recipe import ResolvedRecipe
    from retarget.recipe.model import MotionsSection
    from retarget.registry import Registry

SETTINGS = "train_settings.json"
"""How a run trains beyond its recipe (checkpoint interval, logging), kept by ``--resume``."""
DEFAULT_SETTINGS: dict[str, Any] = {"checkpoint_every": 10, "tensorboard": True}


def check_start(*, resume: str | Path | None, init_from: bool, teacher: bool, expert: bool,
                recipe_changes: bool, num_envs: bool) -> None:  # fmt: skip
    """Refuse combinations that cannot mean one run, naming what to drop (``resume``: the
    run being resumed, as given)."""
    if teacher and expert:
        raise RecipeError("--teacher and --expert are two ways to learn; use one of them")
    if resume and (init_from or teacher or expert):
        raise RecipeError(
            "--resume continues a run with its own weights and recipe; --init-from and "
            "--teacher/--expert start a new one",
            hint="use one of them",
        )
    if resume and recipe_changes:
        raise RecipeError(
            "--resume continues with the run's own recipe.lock.yaml; "
            "recipe files and --set do not apply",
            file=str(Path(resume) / LOCK),
        )
    if resume and num_envs:
        raise RecipeError(
            "--resume continues with the run's own environment count",
            file=str(Path(resume) / LOCK),
            hint="drop --num-envs (a checkpoint holds every environment's state)",
        )


def check_motion_source(motions: MotionsSection) -> None:
    """Refuse a recipe that picks motion files by pattern but names no files to pick from
    (no ``motions.path``, no ``$RETARGET_DATA``): it would train on the packaged generated
    clips, which no pattern was written for. A shipped model's lock is such a recipe (its
    data is left out of the package), so fine-tuning one from its lock needs ``--motions``."""
    import os

    from retarget.motion.sources import ENV_VAR

    if motions.path or os.environ.get(ENV_VAR, "").strip():
        return
    picks = {k: v for k, v in (("include", motions.include), ("exclude", motions.exclude),
                               ("weights", motions.weights)) if v}  # fmt: skip
    if picks:
        shown = ", ".join(f"motions.{k}={v}" for k, v in picks.items())
        raise RecipeError(
            f"the recipe picks motion files ({shown}) but names none to pick from "
            f"(motions.path is empty and ${ENV_VAR} unset), so it would train on the packaged "
            "generated clips; a shipped model's lock leaves its data out",
            field="motions.path",
            hint="give --motions PATH (e.g. ../shared/data/mocap_corpus), or drop the "
            "patterns (--set motions.include=[] --set motions.exclude=[] --set "
            "motions.weights={}) to train on the "
            "generated clips",
        )


def fields_newer_than_lock(recipe_file: str | Path | None, resolved: ResolvedRecipe) -> list[str]:
    """Notes for a run started from a ``recipe.lock.yaml`` recorded before a field of
    :data:`~retarget.train.load.BEFORE_FIELDS` existed: the new run takes today's default,
    which may not be what the run it came from did (a teacher fine-tuned from an old lock
    would otherwise move to hinged elbows unannounced, and its students' references with it).
    A field set on the command line (``--set SECTION.FIELD=...``) gets no note."""
    from retarget.recipe.source import LOCK_SECTION, parse_text
    from retarget.train.load import BEFORE_FIELDS

    if recipe_file is None or not Path(recipe_file).is_file():
        return []
    path = Path(recipe_file)
    text = path.read_text(encoding="utf-8", errors="replace")
    if f"\n{LOCK_SECTION}:" not in "\n" + text:
        return []
    data = parse_text(text, str(path), path.suffix).data
    notes = []
    for section, field, before in BEFORE_FIELDS:
        part = data.get(section)
        key = f"{section}.{field}"
        if not isinstance(part, dict) or field in part or key in resolved.source.overrides:
            continue
        now = getattr(getattr(resolved.recipe, section), field)
        if now != before:
            was = _as_set(before)
            notes.append(
                f"{path} was locked before {key} existed: this run takes today's default "
                f"({_as_set(now)}), the run it records had {was} (--set {key}={was} trains "
                "as it did)"
            )
    return notes


def _as_set(value: object) -> str:
    """A value as ``--set`` reads it (YAML: booleans lower case)."""
    return str(value).lower() if isinstance(value, bool) else str(value)


def start_assignments(*, teacher: str | None, expert: str | None, num_envs: int | None,
                      threads: int | None) -> list[str]:  # fmt: skip
    """The recipe overrides that the start flags stand for, so ``recipe.lock.yaml`` records
    exactly what ran."""
    flags = []
    if teacher:
        flags.append(f"algorithm={json.dumps({'type': 'dagger', 'teacher': str(teacher)})}")
    if expert:
        resolved = str(Path(expert).resolve())
        flags.append(f"algorithm={json.dumps({'type': 'expert_bc', 'expert': resolved})}")
    if num_envs is not None:
        flags.append(f"env.num_envs={num_envs}")
    if threads is not None:
        flags.append(f"sim.threads={threads}")
    return flags


def run_name(resolved: ResolvedRecipe, sensors: list[str] | None = None) -> str:
    """The recipe's ``name``, else one made of the character, the sensors the policy reads
    (``sensors``; default: those of the actor group: a teacher's own are not in the name),
    the recipe file when it is not the packaged default, the scene, observers and algorithm."""
    if resolved.recipe.name:
        return resolved.recipe.name
    from retarget.recipe.defaults import is_packaged

    if sensors is None:
        groups = resolved.recipe.env.groups or {}
        sensors = [c.entry.name for c in resolved.of_kind("sensor")
                   if "actor" not in groups or c.entry.name in groups["actor"]]  # fmt: skip
    character = resolved.character.entry.name
    stem = Path(resolved.source.path).stem
    packaged_default = is_packaged(resolved.source.path) and stem in ("default", character)

    def names(kind: str) -> list[str]:
        return [c.entry.name for c in resolved.of_kind(kind)]

    scenes, algorithms = names("scene"), names("algorithm")
    return default_run_name(
        character,
        sensors,
        recipe=None if packaged_default else stem.removeprefix(f"{character}_"),
        scene=scenes[0] if scenes else None,
        observers=names("observer"),
        algorithm=algorithms[0] if algorithms else None,
    )


def resume_recipe(run: Path, registry: Registry, threads: int | None
                  ) -> tuple[ResolvedRecipe, list[str]]:  # fmt: skip
    """The run's locked recipe (``threads``, which changes only the speed, recorded in it)
    and a line for every plugin whose installed version differs from the run's start."""
    from retarget.train.load import locked_recipe

    changes = [f"sim.threads={threads}"] if threads is not None else []
    resolved, lock = locked_recipe(run, registry, assignments=changes)
    moved = []
    for path, info in lock.get("plugins", {}).items():
        comp = resolved.components.get(path)
        if comp is not None and comp.entry.version != info.get("version"):
            moved.append(f"{path}: plugin '{comp.entry.name}' is {comp.entry.distribution} "
                         f"{comp.entry.version}, the run started with {info.get('version')}")
    return resolved, moved


def run_settings(run_dir: Path, given: dict[str, Any], *, resume: bool) -> dict[str, Any]:
    """The run's settings: flags given now, else what the run recorded (on ``--resume``), else
    the defaults; written back so the next resume keeps them."""
    path = run_dir / SETTINGS
    recorded: dict[str, Any] = {}
    if resume and path.exists():
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise RecipeError(f"cannot read the run's settings: {exc}", file=str(path)) from None
        every = data.get("checkpoint_every") if isinstance(data, dict) else None
        tb = data.get("tensorboard") if isinstance(data, dict) else None
        if not (isinstance(every, int) and 1 <= every <= 10**6 and isinstance(tb, bool)):
            raise RecipeError(
                "the run's settings must be {checkpoint_every: 1..1000000, tensorboard: bool}",
                file=str(path),
            )
        recorded = {"checkpoint_every": every, "tensorboard": tb}
    settings = {
        key: given[key] if given.get(key) is not None else recorded.get(key, default)
        for key, default in DEFAULT_SETTINGS.items()
    }
    path.write_text(json.dumps(settings) + "\n", encoding="utf-8")
    return settings
