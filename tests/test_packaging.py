"""The distribution's package list and entry points are complete and load strictly."""

from __future__ import annotations

import importlib
import tomllib

from helpers import REPO

from retarget.registry.loader import load_plugins
from retarget.testing.toolkit import (
    PROVISIONAL,
    TOOLKIT,
    provisional_imports,
    tier,
    toolkit_violations,
)


def _pyproject() -> dict:
    return tomllib.loads((REPO / "pyproject.toml").read_text())


def test_every_package_directory_is_listed() -> None:
    listed = set(_pyproject()["tool"]["setuptools"]["packages"])
    found = set()
    for top, dotted in (("core", "retarget"), ("plugins", "retarget.plugins")):
        for init in (REPO / top).rglob("__init__.py"):
            rel = init.parent.relative_to(REPO / top).parts
            found.add(".".join((dotted, *rel)))
    missing = sorted(found - listed)
    assert not missing, f"add to [tool.setuptools] packages in pyproject.toml: {missing}"
    stale = sorted(listed - found)
    assert not stale, f"listed packages without an __init__.py: {stale}"


def test_builtin_entry_points_all_load_strictly() -> None:
    eps = _pyproject()["project"]["entry-points"]["retarget"]
    registry = load_plugins(strict=True)
    assert not registry.problems
    providers = {e.plugin for e in registry if e.distribution == "retarget"}
    assert set(eps) <= providers, f"entry points registering nothing: {set(eps) - providers}"


def test_plugins_import_only_the_declared_toolkit() -> None:
    """Built-in plugins and the third-party example import from retarget only what
    :data:`retarget.testing.toolkit.TOOLKIT` declares (an allow-list: anything else fails)."""
    builtins = list((REPO / "plugins").rglob("*.py"))
    example = list((REPO / "examples" / "third_party_plugin" / "src").rglob("*.py"))
    bad = toolkit_violations(builtins, "retarget.plugins")
    bad += toolkit_violations(example, "retarget_head_height")
    assert not bad, "\n".join(bad)


def test_toolkit_guard_refuses_an_internal_import(tmp_path) -> None:
    plugin = tmp_path / "plugin.py"
    plugin.write_text("from retarget.env.managers import RewardManager\nimport retarget.cli.main\n")
    assert len(toolkit_violations([plugin], "mine")) == 2


def test_toolkit_modules_exist() -> None:
    for entry in TOOLKIT:
        importlib.import_module(entry.removesuffix(".*"))


def test_ci_runs_the_readme_test_command() -> None:
    readme = (REPO / "README.md").read_text()
    ci = (REPO / ".ci" / "run").read_text().strip().splitlines()
    assert ci[-1] in readme, f"README must show the test command CI runs: {ci[-1]!r}"


def test_toolkit_tiers() -> None:
    """Every provisional entry is part of the toolkit; the plugin base classes are stable."""
    assert set(TOOLKIT) >= PROVISIONAL
    assert tier("retarget") == tier("retarget.kinds.reward") == "stable"
    assert tier("retarget.learn.ppo") == tier("retarget.env.build") == "provisional"
    assert tier("retarget.env.managers") is None  # not in the toolkit at all


def test_provisional_imports_are_listed(tmp_path) -> None:
    plugin = tmp_path / "plugin.py"
    plugin.write_text("import retarget\nfrom retarget.learn.networks import mlp\n"
                      "from retarget.character.builder import BodyBuilder\n")
    found = provisional_imports([plugin])
    assert len(found) == 1 and "retarget.learn" in found[0] and ":2 " in found[0]
