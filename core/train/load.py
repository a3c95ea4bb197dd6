"""Loading a trained run back: its locked recipe, a fresh env, and the trained algorithm."""

from __future__ import annotations

import copy
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import yaml

from retarget.env import RetargetEnv
from retarget.env.build import env_from_recipe
from retarget.errors import RecipeError
from retarget.kinds import Algorithm
from retarget.kinds.lookup import PluginLookup
from retarget.kinds.step import StepPlugin
from retarget.motion.clip import MotionClip
from retarget.recipe import ResolvedRecipe, apply_overrides, parse_text, resolve
from retarget.recipe.source import LOCK_SECTION
from retarget.train.checkpoint import load_checkpoint
from retarget.train.run_dir import LOCK, latest_checkpoint, resolve_run

BEFORE_FIELDS: tuple[tuple[str, str, object], ...] = (
    ("env", "devices", "person"),  # its devices were at the performer's size
    ("motions", "level_feet", False),  # its references kept the file's foot tilt
    ("env", "hinge_elbows", False),  # its references' elbows bent by the angle alone
)
"""Fields added after runs were recorded, with the value that says what such a run did."""


def fill_before_fields(recipe: dict) -> None:
    """Give a recorded recipe (a run's lock, an expert directory's header) each field of
    :data:`BEFORE_FIELDS` it lacks, with the value that says what it did before the field."""
    for section, field, value in BEFORE_FIELDS:
        part = recipe.get(section)
        if isinstance(part, dict) and field not in part:
            part[field] = value


def locked_recipe(
    run: Path, registry: PluginLookup, *, scene: str | None = None, assignments: Sequence[str] = ()
) -> tuple[ResolvedRecipe, dict]:
    """The run's ``recipe.lock.yaml`` resolved against the installed plugins, and its lock
    section (plugin versions the run started with).

    ``scene`` and ``assignments`` (``--scene``/``--set``) change the recipe before it is
    resolved, e.g. to watch a policy in a scene it was not trained in; errors name the flag.
    """
    path = run / LOCK
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise RecipeError("the run's lock file is not UTF-8 text", file=str(path)) from None
    except OSError as exc:
        raise RecipeError(f"cannot read the run's lock file: {exc}", file=str(path)) from None
    source = parse_text(text, str(path), ".yaml")  # plain data only, bounded, no duplicates
    lock = yaml.safe_load(text).get(LOCK_SECTION) or {}
    if not isinstance(lock, dict):
        raise RecipeError(f"'{LOCK_SECTION}' must be a mapping", file=str(path))
    fill_before_fields(source.data)  # a run locked before a field existed
    source = apply_overrides(source, shorthands={"scene": scene}, assignments=assignments)
    return resolve(source, registry), lock


STEP_KINDS = ("sensor", "observer", "reward", "termination")
"""The plugin kinds whose components may pin their config when a run is locked."""


def prepared_recipe(resolved: ResolvedRecipe, registry: PluginLookup) -> ResolvedRecipe:
    """``resolved`` as a new run locks it: every step plugin's
    :meth:`~retarget.kinds.step.StepPlugin.pinned_config` (a sensor that names another run
    fixes the checkpoint it reads), then the algorithm's
    :meth:`~retarget.kinds.Algorithm.prepare_recipe` (a distillation run given its
    teacher's sensors), resolved again; unchanged when nothing changes."""
    pins = {}
    for path, comp in resolved.components.items():
        if comp.entry.kind in STEP_KINDS:
            plugin = comp.instantiate()
            assert isinstance(plugin, StepPlugin)
            pinned = plugin.pinned_config(registry)
            if pinned is not None:
                pins[path] = pinned
    before = resolved.to_dict()
    after = resolved.to_dict(pins)
    if "algorithm" in resolved.components:
        algorithm = resolved.component("algorithm").instantiate()
        assert isinstance(algorithm, Algorithm)
        after = algorithm.prepare_recipe(copy.deepcopy(after), registry)
    if after == before:
        return resolved
    source = resolved.source
    text = yaml.safe_dump(after, sort_keys=False)
    again = parse_text(text, source.path, ".yaml")
    again.overrides.update(source.overrides)
    return resolve(again, registry)


@dataclass
class LoadedRun:
    run: Path
    checkpoint: Path
    resolved: ResolvedRecipe
    env: RetargetEnv
    algorithm: Algorithm
    progress: dict


def load_run(
    path: str | Path,
    registry: PluginLookup,
    *,
    num_envs: int = 1,
    motions: str | None = None,
    clips: list[MotionClip] | None = None,
    terminations: bool = False,
    checkpoint: str | Path | None = None,
    scene: str | None = None,
    assignments: Sequence[str] = (),
    include: Sequence[str] | None = None,
    exclude: Sequence[str] | None = None,
) -> LoadedRun:
    """A trained run ready to act: env built from its recipe (optionally on other motions, or
    with ``scene``/``assignments`` changing the recipe; see :func:`locked_recipe`)."""
    run = resolve_run(path)
    resolved, _ = locked_recipe(run, registry, scene=scene, assignments=assignments)
    if "algorithm" not in resolved.components:
        raise RecipeError("the run's recipe has no algorithm", file=str(run / LOCK))
    ckpt = Path(checkpoint) if checkpoint is not None else latest_checkpoint(run)
    state = load_checkpoint(ckpt)
    env = env_from_recipe(
        resolved,
        num_envs=num_envs,
        motions=motions,
        clips=clips,
        terminations=terminations,
        registry=registry,
        include=include,
        exclude=exclude,
        weighted=False,
    )
    algorithm = resolved.component("algorithm").instantiate()
    assert isinstance(algorithm, Algorithm)
    algorithm.connect(registry)
    algorithm.setup(env)
    try:
        algorithm.load_state_dict(state["algorithm"])
    except (RuntimeError, KeyError, ValueError) as exc:
        changed = [*([f"--scene {scene}"] if scene else []), *(f"--set {a}" for a in assignments)]
        raise RecipeError(
            f"checkpoint {ckpt} does not fit the policy this recipe builds "
            f"(observation sizes {dict(env.obs_dims)}): {_first_mismatch(exc)}",
            file=str(run / LOCK),
            hint=(f"{', '.join(changed)} changed what the policy observes; change only what it "
                  "does not see (a scene seen through the same observers, clips)")
            if changed else None,
        ) from None
    return LoadedRun(run, ckpt, resolved, env, algorithm, state.get("progress", {}))


def _first_mismatch(exc: Exception) -> str:
    """The informative line of torch's ``load_state_dict`` error (its first line only says
    which module failed)."""
    lines = [line.strip() for line in str(exc).splitlines() if line.strip()]
    detail = [line for line in lines if "size mismatch" in line or "key" in line.lower()]
    return (detail or lines or [type(exc).__name__])[0]
