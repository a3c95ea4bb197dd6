"""Binding the estimated_body sensor leaves the global torch RNG as the trainer seeded it."""

from __future__ import annotations

import torch

from retarget.env.build import env_from_recipe
from retarget.recipe import load
from retarget.registry.loader import load_plugins


def test_binding_does_not_reseed_the_global_generator() -> None:
    registry = load_plugins(strict=True)
    resolved = load(None, registry, shorthands={"sensors": "estimated_body"}, assignments=[])
    torch.manual_seed(1234)
    expected = torch.rand(3)
    torch.manual_seed(1234)
    env_from_recipe(resolved, num_envs=1, threads=1, registry=registry)  # binds the sensor
    assert torch.equal(torch.rand(3), expected)
