"""Loading a trained run back: its locked recipe, a fresh env, and the trained algorithm."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import yaml

from retarget.checkpoint import load_checkpoint
from retarget.env import RetargetEnv
from retarget.env.build import env_from_recipe
from retarget.errors import RecipeError
from retarget.kinds import Algorithm
from retarget.motion.clip import MotionClip
from retarget.recipe import ResolvedRecipe, parse_text, resolve
from retarget.registry import Registry
from retarget.train.run_dir import LOCK, latest_checkpoint, resolve_run


def locked_recipe(run: Path, registry: Registry) -> tuple[ResolvedRecipe, dict]:
    """The run's ``recipe.lock.yaml`` resolved against the installed plugins, and its lock
    section (plugin versions the run started with)."""
    data = yaml.safe_load((run / LOCK).read_text())
    lock = data.pop("_lock", {})
    source = parse_text(yaml.safe_dump(data, sort_keys=False), str(run / LOCK), ".yaml")
    return resolve(source, registry), lock


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
    registry: Registry,
    *,
    num_envs: int = 1,
    motions: str | None = None,
    clips: list[MotionClip] | None = None,
    terminations: bool = False,
    checkpoint: str | Path | None = None,
) -> LoadedRun:
    """A trained run ready to act: env built from its recipe (optionally on other motions)."""
    run = resolve_run(path)
    resolved, _ = locked_recipe(run, registry)
    if "algorithm" not in resolved.components:
        raise RecipeError("the run's recipe has no algorithm", file=str(run / LOCK))
    ckpt = Path(checkpoint) if checkpoint is not None else latest_checkpoint(run)
    state = load_checkpoint(ckpt)
    env = env_from_recipe(
        resolved, num_envs=num_envs, motions=motions, clips=clips, terminations=terminations
    )
    algorithm = resolved.component("algorithm").instantiate()
    assert isinstance(algorithm, Algorithm)
    algorithm.setup(env)
    algorithm.load_state_dict(state["algorithm"])
    return LoadedRun(run, ckpt, resolved, env, algorithm, state.get("progress", {}))
