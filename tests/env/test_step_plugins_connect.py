"""Step plugins built from a recipe receive the invocation's registry (``connect``) before
``bind``, so a plugin that builds other plugins (``estimated_body`` wrapping a sensor)
resolves them against the recipe's plugin set instead of reloading every entry point."""

from __future__ import annotations

from helpers import TINY

from retarget.env.build import env_from_recipe
from retarget.recipe import parse_text, resolve
from retarget.registry.loader import load_plugins


def test_every_step_plugin_of_the_env_is_connected_to_the_recipes_registry() -> None:
    registry = load_plugins()
    text = TINY.replace("sensors: [three_point]", "sensors: [three_point, estimated_body]")
    resolved = resolve(parse_text(text, "tiny.yaml", ".yaml"), registry)
    env = env_from_recipe(resolved, num_envs=2, threads=1, registry=registry)
    plugins = [*env.sensors, *env.rewards.terms.values(), *env.terminations.terms.values()]
    assert {p.name for p in env.sensors} == {"three_point", "estimated_body"}
    assert all(p.registry is registry for p in plugins), [p.name for p in plugins
                                                          if p.registry is not registry]
    wrapped = next(s for s in env.sensors if s.name == "estimated_body")._inner
    assert wrapped and wrapped[0].name == "three_point"


def test_a_plugin_built_outside_a_recipe_has_no_registry() -> None:
    from retarget.plugins.sensors.devices import Hmd

    assert Hmd().registry is None
