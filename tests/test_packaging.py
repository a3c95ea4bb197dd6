"""The distribution's package list and entry points are complete and load strictly."""

from __future__ import annotations

import tomllib

from helpers import REPO

from retarget.registry.loader import load_plugins


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


def test_builtins_use_only_the_public_api() -> None:
    """Built-in plugins import retarget's public names, never private helpers."""
    offenders = []
    for path in (REPO / "plugins").rglob("*.py"):
        text = path.read_text()
        if "from retarget._" in text or "import retarget._" in text:
            offenders.append(str(path.relative_to(REPO)))
    assert not offenders, offenders


def test_ci_runs_the_readme_test_command() -> None:
    readme = (REPO / "README.md").read_text()
    ci = (REPO / ".ci" / "run").read_text().strip().splitlines()
    assert ci[-1] in readme, f"README must show the test command CI runs: {ci[-1]!r}"
