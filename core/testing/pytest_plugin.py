"""pytest fixtures shipped with retarget (registered through the ``pytest11`` entry point).

Any package that has retarget installed gets them without a conftest import.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from retarget.kinds.state import StepContext
from retarget.registry import Registry
from retarget.registry.loader import load_plugins
from retarget.sim.world import World
from retarget.testing.fakes import fake_context, tiny_world


@pytest.fixture
def retarget_registry() -> Registry:
    """A fresh registry of every installed plugin, loaded strictly (a broken plugin fails)."""
    return load_plugins(strict=True)


@pytest.fixture(name="tiny_world")
def tiny_world_fixture() -> World:
    """The compiled test character on a flat floor, with its layout."""
    return tiny_world()


@pytest.fixture
def fake_ctx() -> Callable[..., StepContext]:
    """Factory: ``fake_ctx(num_envs=4, seed=0, layout=None)`` -> a valid random StepContext."""

    def make(num_envs: int = 4, seed: int = 0, layout=None) -> StepContext:
        return fake_context(layout, num_envs, seed=seed)

    return make
