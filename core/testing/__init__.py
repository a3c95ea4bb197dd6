"""The public plugin contract suite, for retarget's own plugins and third-party packages.

Use it in a test module::

    from retarget.testing import parametrize_with_checks
    from my_package import MyReward

    @parametrize_with_checks([MyReward])
    def test_contract(plugin, check):
        check(plugin)

or call :func:`check_plugin` directly. Checks depend on the plugin's kind (see
:mod:`retarget.testing.checks`); test ids read ``MyReward-check_batch_invariance`` so
``pytest -k`` selects single checks. Fixtures (``retarget_registry``, ``tiny_world``,
``fake_ctx``) are available in any test session once retarget is installed.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from retarget.testing.checks import checks_for, plugin_class
from retarget.testing.fakes import FakeVecEnv, FlatScene, TinyCharacter, fake_context, tiny_world
from retarget.testing.guard import NoPerEnvLoops, VectorisationError


def check_plugin(plugin: object, *, installed: bool = True) -> None:
    """Run every check for ``plugin`` (a class or configured instance); raise on the first failure.

    ``installed=False`` skips the check that the plugin is reachable through an installed entry
    point (for plugins defined inside a test module).
    """
    for check in checks_for(plugin, installed=installed):
        try:
            check(plugin)
        except AssertionError as exc:
            name = plugin_class(plugin).__name__
            raise AssertionError(f"{name} failed {check.__name__}: {exc}") from exc


def parametrize_with_checks(
    plugins: Sequence[object], *, installed: bool = True
) -> Callable[[Callable], Callable]:
    """A ``pytest.mark.parametrize`` over (plugin, check) pairs with readable ids."""
    import pytest

    params = []
    for plugin in plugins:
        for check in checks_for(plugin, installed=installed):
            label = f"{plugin_class(plugin).__name__}-{check.__name__}"
            params.append(pytest.param(plugin, check, id=label))
    return pytest.mark.parametrize(("plugin", "check"), params)


__all__ = [
    "FakeVecEnv",
    "FlatScene",
    "NoPerEnvLoops",
    "TinyCharacter",
    "VectorisationError",
    "check_plugin",
    "checks_for",
    "fake_context",
    "parametrize_with_checks",
    "tiny_world",
]
