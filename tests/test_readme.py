"""README.md as a newcomer meets it: its recipe and plugin examples work as written, every
`retarget ...` line it shows is a valid command, and the quick ones run."""

from __future__ import annotations

import re
import shlex

import pytest
from helpers import REPO

from retarget.cli.main import build_parser, main
from retarget.recipe import load
from retarget.registry.loader import PluginLoadWarning, load_plugins
from retarget.testing import checks

README = (REPO / "README.md").read_text(encoding="utf-8")
BLOCKS = re.findall(r"```(\w+)\n(.*?)```", README, flags=re.S)


def _blocks(lang: str) -> list[str]:
    return [body for kind, body in BLOCKS if kind == lang]


def _commands() -> list[str]:
    """Every `retarget ...` line of the bash blocks (continuations joined, comments cut)."""
    found = []
    for body in _blocks("bash"):
        for line in body.replace("\\\n", " ").splitlines():
            line = line.split(" #")[0].split(">")[0].strip()
            if line.startswith("retarget "):
                found.append(line)
    return found


def test_the_readme_shows_its_examples() -> None:
    assert len(_blocks("yaml")) >= 2 and len(_blocks("python")) >= 2
    assert len(_commands()) >= 20


@pytest.mark.parametrize("line", _commands())
def test_every_command_line_in_the_readme_parses(line: str) -> None:
    parser = build_parser(load_plugins())
    args = parser.parse_args(shlex.split(line)[1:])  # argparse exits on an unknown flag
    assert getattr(args, "handler", None) is not None, line


def test_the_recipe_example_trains_with_its_characters_rewards(tmp_path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "my.yaml").write_text(_blocks("yaml")[0])
    registry = load_plugins()
    resolved = load("my.yaml", registry, shorthands={}, assignments=[])
    rewards = {k.split(".", 1)[1]: c for k, c in resolved.components.items() if "rewards." in k}
    assert rewards["action_diff"].config.weight == 0.1  # what the file says
    assert rewards["smooth"].entry.name == "action_min"
    assert {"joint_pos", "link_pos", "fail_penalty"} <= set(rewards)  # from dino's recipe
    assert "algorithm" in resolved.components and "terminations.fall" in resolved.components
    assert main(["recipe", "validate", "my.yaml", "--character", "dino", "--sensors", "hmd",
                 "--set", "seed=3"]) == 0  # fmt: skip
    assert main(["train", "my.yaml", "--steps", "16", "--set", "env.num_envs=2",
                 "--set", "algorithm.rollout_steps=8", "--set", "algorithm.minibatch_size=16",
                 "--no-tensorboard"]) == 0  # fmt: skip
    assert (tmp_path / "runs").is_dir()


def test_the_scene_example_is_a_valid_recipe(tmp_path) -> None:
    path = tmp_path / "scene.yaml"
    path.write_text(_blocks("yaml")[1])
    assert main(["recipe", "validate", str(path)]) == 0


@pytest.mark.parametrize("argv", [["plugins"], ["plugins", "show", "reward", "action_diff"],
                                  ["recipe", "show"], ["recipe", "schema"]])  # fmt: skip
def test_the_quick_commands_run(argv, capsys) -> None:
    assert main(argv) == 0
    assert capsys.readouterr().out.strip()


def test_the_plugin_in_20_lines_beside_the_installed_example(make_dist, capsys) -> None:
    source = _blocks("python")[0]
    suffix = make_dist("my-package", {"head_height": source})  # the entry point README names
    with pytest.warns(PluginLoadWarning, match="head_height"):
        registry = load_plugins(strict=False)
    assert "head_height" not in registry.names("reward")  # the example has it too: neither
    assert main(["plugins"]) == 0  # the CLI still works
    assert "warning:" in capsys.readouterr().err
    module = __import__(f"head_height_{suffix}")
    for check in checks.checks_for(module.HeadHeight, installed=False):
        check(module.HeadHeight)  # the contract suite, as the README's own test runs it


def test_the_callbacks_example_is_a_valid_recipe_and_its_variant_too(tmp_path) -> None:
    (block,) = [b for b in _blocks("yaml") if "callbacks:" in b]
    registry = load_plugins()
    for i, text in enumerate((block, block.replace("[events]", "[{type: events, every: 10}]"))):
        path = tmp_path / f"cb{i}.yaml"
        path.write_text(text)
        resolved = load(str(path), registry, shorthands={}, assignments=[])
        (cb,) = resolved.of_kind("callback")
        assert cb.entry.name == "events"
        assert cb.config.every == (1, 10)[i]
