"""Every installed plugin, built-in or third-party, passes the public contract suite."""

from __future__ import annotations

from retarget.registry.loader import load_plugins
from retarget.testing import parametrize_with_checks

INSTALLED = [entry.cls for entry in load_plugins(strict=True)]


@parametrize_with_checks(INSTALLED)
def test_installed_plugin_contract(plugin, check) -> None:
    check(plugin)
