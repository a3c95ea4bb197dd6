"""Installed plugins load in isolation: broken ones warn (or fail in strict mode), never crash."""

from __future__ import annotations

import pytest

from retarget.cli.main import main
from retarget.errors import PluginError
from retarget.registry.loader import PluginLoadWarning, load_plugins

GOOD = """
import retarget
from retarget.plugins.rewards.action import ActionMin

class Calm(ActionMin):
    '''Rewards calm actions.'''
    name = "calm"

@retarget.hookimpl
def register_rewards(register):
    register(Calm)
"""

IMPORT_ERROR = "import retarget\nimport does_not_exist_anywhere\n"

RAISES = """
import retarget

@retarget.hookimpl
def register_rewards(register):
    raise RuntimeError("boom inside the hook")
"""

UNKNOWN_HOOK = """
import retarget

@retarget.hookimpl
def register_robots(register):
    pass
"""

DUPLICATE = """
import retarget
from retarget.plugins.rewards.action import ActionMin

class Again(ActionMin):
    '''Same name as a built-in.'''
    name = "action_min"

@retarget.hookimpl
def register_rewards(register):
    register(Again)
"""

NOT_A_PLUGIN = """
import retarget

@retarget.hookimpl
def register_rewards(register):
    register(dict, name="dicty")
"""


def test_good_third_party_plugin_is_attributed(make_dist) -> None:
    make_dist("retarget-calm", {"calm": GOOD}, version="2.3")
    entry = load_plugins(strict=True).get("reward", "calm")
    assert (entry.distribution, entry.version, entry.plugin) == ("retarget-calm", "2.3", "calm")


@pytest.mark.parametrize(
    ("source", "needle"),
    [
        (IMPORT_ERROR, "failed to import"),
        (RAISES, "boom inside the hook"),
        (UNKNOWN_HOOK, "unknown hook"),
        (NOT_A_PLUGIN, "not a subclass"),
    ],
    ids=["import-error", "raises-in-hook", "unknown-hook", "not-a-plugin"],
)
def test_broken_plugin_warns_and_the_rest_loads(make_dist, source, needle) -> None:
    make_dist("retarget-broken", {"broken": source, "calm": GOOD})
    with pytest.warns(PluginLoadWarning, match=needle) as caught:
        registry = load_plugins(strict=False)
    assert any("retarget-broken" in str(w.message) for w in caught)
    assert "calm" in registry.names("reward")
    assert "action_diff" in registry.names("reward")
    with pytest.raises(PluginError, match=needle):
        load_plugins(strict=True)


def test_broken_plugin_leaves_cli_working_and_strict_fails(make_dist, capsys, monkeypatch) -> None:
    make_dist("retarget-broken", {"broken": RAISES})
    assert main(["plugins"]) == 0
    captured = capsys.readouterr()
    assert "action_diff" in captured.out
    assert "warning:" in captured.err and "retarget-broken" in captured.err
    assert "boom inside the hook" in captured.err
    assert main(["--strict-plugins", "plugins"]) == 2
    err = capsys.readouterr().err
    assert "error:" in err and "broken" in err and "Traceback" not in err
    monkeypatch.setenv("RETARGET_STRICT_PLUGINS", "1")
    assert main(["plugins"]) == 2


def test_a_duplicate_of_a_built_in_name_keeps_the_built_in(make_dist, capsys) -> None:
    make_dist("retarget-dupe", {"dupe": DUPLICATE})
    with pytest.warns(PluginLoadWarning) as caught:
        registry = load_plugins(strict=False)
    text = " ".join(str(w.message) for w in caught)
    assert "reward name 'action_min' of a built-in" in text and "retarget-dupe" in text
    assert registry.get("reward", "action_min").distribution == "retarget"
    assert "action_diff" in registry.names("reward")  # everything else still loads
    with pytest.raises(PluginError, match="of a built-in"):
        load_plugins(strict=True)
    assert main(["plugins"]) == 0  # the CLI still starts
    assert "warning:" in capsys.readouterr().err


def test_an_entry_point_name_taken_twice_loads_neither(make_dist) -> None:
    make_dist("retarget-calm-a", {"calm": GOOD})
    make_dist("retarget-calm-b", {"calm": GOOD})
    with pytest.warns(PluginLoadWarning, match="neither is loaded"):
        registry = load_plugins(strict=False)
    assert "calm" not in registry.names("reward")


EXITS = "import sys\nsys.exit(3)\n"
BASE_EXCEPTION = "class Odd(BaseException):\n    pass\n\nraise Odd('from import')\n"


def test_sys_exit_or_base_exception_at_import_is_a_broken_plugin(make_dist, capsys) -> None:
    make_dist("retarget-exits", {"exits": EXITS, "odd": BASE_EXCEPTION})
    with pytest.warns(PluginLoadWarning) as caught:
        registry = load_plugins(strict=False)
    text = " ".join(str(w.message) for w in caught)
    assert "SystemExit: 3" in text and "Odd: from import" in text
    assert "action_diff" in registry.names("reward")
    assert main(["plugins"]) == 0
    assert "action_diff" in capsys.readouterr().out


def test_allowlist_limits_third_party_distributions(make_dist, monkeypatch) -> None:
    make_dist("retarget-calm", {"calm": GOOD})
    monkeypatch.setenv("RETARGET_LOAD_PLUGINS", "")
    names = load_plugins(strict=True).names("reward")
    assert "calm" not in names and "action_diff" in names
    monkeypatch.setenv("RETARGET_LOAD_PLUGINS", "retarget-calm")
    assert "calm" in load_plugins(strict=True).names("reward")


def test_every_plugin_with_an_unknown_hook_is_named_and_left_out(make_dist) -> None:
    """Two plugins with unknown hooks: both are warned about and left out (only the first
    was handled; the second then broke every later lookup), and the good one loads."""
    make_dist("retarget-odd", {"odd_a": UNKNOWN_HOOK, "odd_b": UNKNOWN_HOOK, "calm": GOOD})
    with pytest.warns(PluginLoadWarning) as seen:
        registry = load_plugins(strict=False)
    named = " ".join(str(w.message) for w in seen)
    assert "odd_a" in named and "odd_b" in named and named.count("implements an unknown hook") == 2
    assert registry.get("reward", "calm").distribution == "retarget-odd"


SHADOW = """
import retarget
from retarget.plugins.rewards.action import ActionMin

class Fake(ActionMin):
    '''Claims a built-in's name.'''
    name = "action_diff"

@retarget.hookimpl
def register_rewards(register):
    register(Fake)
"""


def test_a_built_in_cannot_be_shadowed(make_dist) -> None:
    """A package whose entry point is named like a built-in (``ppo``) and whose plugin takes a
    built-in's name (``action_diff``) leaves both built-ins working and is named; both were
    disabled before."""
    make_dist("retarget-shadow", {"ppo": GOOD, "shadow": SHADOW})
    with pytest.warns(PluginLoadWarning) as seen:
        registry = load_plugins(strict=False)
    named = " ".join(str(w.message) for w in seen)
    assert "retarget-shadow" in named and "built-in" in named
    assert registry.get("algorithm", "ppo").distribution == "retarget"
    assert registry.get("reward", "action_diff").distribution == "retarget"
    assert "calm" not in registry.names("reward")  # its entry point was the intruder
    with pytest.raises(PluginError, match="built-in"):
        load_plugins(strict=True)
