"""Building a :class:`RetargetEnv` from a resolved recipe."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from retarget.env.env import RetargetEnv
from retarget.errors import RecipeError
from retarget.kinds import (
    Character,
    MotionFormat,
    Observer,
    RewardTerm,
    Scene,
    Sensor,
    StepPlugin,
    Termination,
)
from retarget.kinds.lookup import PluginLookup
from retarget.motion.clip import MotionClip
from retarget.motion.clip_weights import clip_weights
from retarget.motion.level_feet import with_level_feet
from retarget.motion.mirror import mirror
from retarget.motion.rest_ends import with_rest_ends
from retarget.motion.sources import load_motions
from retarget.recipe import ResolvedRecipe


def motion_formats(
    resolved: ResolvedRecipe, registry: PluginLookup | None
) -> dict[str, MotionFormat]:
    """The readers of a recipe's motions: only the ``motions.format`` component, exactly as
    configured, else every registered format with its defaults (each file read by the one
    whose suffix it has); without a registry, the installed plugins'."""
    if "motions.format" in resolved.components:
        comp = resolved.component("motions.format")
        fmt = comp.instantiate()
        assert isinstance(fmt, MotionFormat)
        return {comp.entry.name: fmt}
    if registry is None:
        from retarget.registry.loader import load_plugins

        registry = load_plugins()
    return registry.motion_formats()


def env_from_recipe(
    resolved: ResolvedRecipe,
    *,
    num_envs: int | None = None,
    threads: int | None = None,
    motions: str | None = None,
    clips: list[MotionClip] | None = None,
    terminations: bool = True,
    registry: PluginLookup | None = None,
    seed: int | None = None,
    include: Sequence[str] | None = None,
    exclude: Sequence[str] | None = None,
    weighted: bool = True,
) -> RetargetEnv:
    """Instantiate every component of ``resolved``, load its motions and build the env.

    ``motions`` replaces the recipe's motion path (evaluation on other clips), ``clips``
    gives the clips themselves (already loaded or generated);
    ``terminations=False`` keeps only clip ends (evaluation follows runs through failures);
    ``registry`` is the invocation's plugins (motion formats come from it); ``seed``
    replaces the recipe's (each rank of a distributed run has its own); ``include`` and
    ``exclude`` pick files by name (default: the recipe's own picks, which apply only to the
    recipe's own path: a held-out set is named with the path that replaces it);
    ``weighted=False`` leaves ``motions.weights`` out: they say how often training draws each
    clip, and a run loaded to act (eval, play, serve) draws none, possibly from other clips.
    """
    recipe = resolved.recipe

    def connected(plugin: Any) -> Any:
        if registry is not None and isinstance(plugin, StepPlugin):
            plugin.connect(registry)
        return plugin

    def made(kind: str) -> list:
        return [connected(c.instantiate()) for c in resolved.of_kind(kind)]

    character = resolved.character.instantiate()
    assert isinstance(character, Character)
    scenes = made("scene")
    rewards = {
        path.split(".", 1)[1]: connected(comp.instantiate())
        for path, comp in resolved.components.items()
        if comp.entry.kind == "reward"
    }
    ends = {
        path.split(".", 1)[1]: connected(comp.instantiate())
        for path, comp in resolved.components.items()
        if comp.entry.kind == "termination" and terminations
    }
    sim = recipe.sim if threads is None else recipe.sim.model_copy(update={"threads": threads})
    options = recipe.env
    if num_envs is not None:
        options = options.model_copy(update={"num_envs": num_envs})
    weights = None
    if clips is None:
        own = motions is None
        clips = load_motions(
            recipe.motions.path if own else motions,
            motion_formats(resolved, registry),
            include=include if include is not None else recipe.motions.include if own else (),
            exclude=exclude if exclude is not None else recipe.motions.exclude if own else (),
        )
        if recipe.motions.level_feet:
            clips = with_level_feet(clips)
        if own and recipe.motions.rest_ends:
            clips = with_rest_ends(clips)
        if own and recipe.motions.mirror:
            clips = [*clips, *(mirror(c) for c in clips)]
        if own and weighted and recipe.motions.weights:
            try:
                weights = clip_weights(clips, recipe.motions.weights)
            except ValueError as err:
                raise RecipeError(str(err), field="motions.weights") from err
    sensors: list[Sensor] = made("sensor")
    observers: list[Observer] = made("observer")
    scene: Scene | None = scenes[0] if scenes else None
    assert all(isinstance(r, RewardTerm) for r in rewards.values())
    assert all(isinstance(t, Termination) for t in ends.values())
    return RetargetEnv(
        character,
        clips,
        sensors=sensors,
        observers=observers,
        rewards=rewards,
        terminations=ends,
        scene=scene,
        options=options,
        sim=sim,
        seed=recipe.seed if seed is None else seed,
        clip_weights=weights,
    )
