"""The ``retarget`` command: listing, showing, recipes, and commands added by plugins."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from retarget.cli.main import main

COMMAND = """
import retarget

class Hello(retarget.Command):
    '''Says hello (a command added by a plugin).'''
    name = "hello"

    def add_arguments(self, parser):
        parser.add_argument("who")

    def run(self, args):
        print(f"hello {args.who}")
        if args.who == "error":
            raise retarget.RecipeError("bad who", field="who")
        if args.who == "bug":
            raise ValueError("a bug in the plugin")
        return 0

@retarget.hookimpl
def register_commands(register):
    register(Hello)
"""

TINY = """
import retarget
from retarget.testing.fakes import TinyCharacter

@retarget.hookimpl
def register_characters(register):
    register(TinyCharacter)
"""


def test_plugins_table_and_json(capsys) -> None:
    assert main(["plugins"]) == 0
    out = capsys.readouterr().out
    assert "action_diff" in out and "retarget" in out
    assert main(["plugins", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    row = next(r for r in rows if r["name"] == "episode_cap")
    assert row["kind"] == "termination" and row["distribution"] == "retarget"


def test_plugins_show_prints_doc_and_fields(capsys) -> None:
    assert main(["plugins", "show", "termination", "episode_cap"]) == 0
    out = capsys.readouterr().out
    assert "max_steps" in out and "300" in out and "Ends an episode" in out
    assert main(["plugins", "show", "reward", "action_dif"]) == 2
    assert "did you mean 'action_diff'" in capsys.readouterr().err


def test_plugin_command_is_added(make_dist, capsys) -> None:
    make_dist("retarget-hello", {"hello": COMMAND})
    assert main(["hello", "world"]) == 0
    assert "hello world" in capsys.readouterr().out
    assert main(["hello", "error"]) == 2
    assert "field 'who'" in capsys.readouterr().err


def test_recipe_verbs(make_dist, tmp_path, capsys) -> None:
    make_dist("retarget-tiny", {"tiny": TINY})
    recipe = tmp_path / "r.yaml"
    recipe.write_text("character: tiny\nrewards:\n  action_min: {k: 0.2}\n")
    assert main(["recipe", "validate", str(recipe)]) == 0
    assert main(["recipe", "show", str(recipe), "--set", "seed=5", "--format", "json"]) == 0
    out = capsys.readouterr().out
    data = json.loads(out[out.index("{") :])
    assert data["seed"] == 5 and data["rewards"]["action_min"] == {
        "type": "action_min",
        "weight": 0.5,
        "k": 0.2,
    }
    assert main(["recipe", "schema"]) == 0
    schema = json.loads(capsys.readouterr().out)
    assert "character_component" in schema["$defs"]
    recipe.write_text("character: tiny\nrewards:\n  action_min: {kk: 0.2}\n")
    assert main(["recipe", "validate", str(recipe)]) == 2
    err = capsys.readouterr().err
    assert str(recipe) in err and "rewards.action_min.kk" in err and "Traceback" not in err


def test_console_script_runs() -> None:
    result = subprocess.run(
        [sys.executable, "-m", "retarget.cli.main", "--version"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert result.returncode == 0 and "retarget" in result.stdout


def test_motion_generate_writes_clips_that_read_back(tmp_path, capsys) -> None:
    import numpy as np

    from retarget import load_plugins
    from retarget.motion.procedural import default_motions
    from retarget.motion.sources import load_motions

    assert main(["motion", "generate", "--out", str(tmp_path), "--names", "sit_stand"]) == 0
    (read,) = load_motions(str(tmp_path), load_plugins().motion_formats())
    (made,) = default_motions(names=("sit_stand",))
    assert read.num_frames == made.num_frames
    np.testing.assert_allclose(read.global_pos, made.global_pos, atol=1e-4)
    assert main(["motion", "generate", "--out", str(tmp_path), "--names", "sitting"]) == 2
    assert "choose from idle" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["train", "--minutes", "nan"], "not finite"),
        (["train", "--steps", "0"], "outside"),
        (["train", "--steps", "-5"], "outside"),
        (["train", "--checkpoint-every", "0"], "outside"),
        (["train", "--num-envs", "100000000"], "outside"),
        (["eval", "run", "--every", "0"], "outside"),
        (["eval", "run", "--max-seconds", "inf"], "not finite"),
        (["eval", "run", "--num-envs", "-1"], "outside"),
        (["play", "run", "--out", "x.png", "--seconds", "0"], "must be >"),
        (["play", "run", "--out", "x.png", "--seconds", "1e9"], "<= 600"),
    ],
)
def test_number_flags_refuse_what_no_run_can_use(argv, needle, capsys) -> None:
    with pytest.raises(SystemExit) as stop:
        main(argv)
    assert stop.value.code == 2
    assert needle in capsys.readouterr().err


@pytest.mark.parametrize("verb", ["train", "eval", "play", "export", "plugins", "recipe"])
def test_subcommand_help_shows_defaults(verb: str, capsys) -> None:
    with pytest.raises(SystemExit) as stop:
        main([verb, "--help"])
    assert stop.value.code == 0
    text = capsys.readouterr().out
    if verb in {"train", "eval", "play"}:
        assert "(default: " in text


def test_a_command_plugin_that_raises_is_named_with_its_distribution(make_dist, capsys) -> None:
    make_dist("retarget-hello", {"hello": COMMAND})
    assert main(["hello", "bug"]) == 2
    err = capsys.readouterr().err
    assert "plugin 'hello from retarget-hello'" in err and "ValueError: a bug in the plugin" in err
    assert "Traceback" not in err and "unexpected failure" not in err
    saved = err.split("traceback is in ")[1].split()[0]
    assert "Traceback" in Path(saved).read_text(encoding="utf-8")


def test_an_unexpected_failure_is_one_line_and_a_traceback_file(monkeypatch, capsys) -> None:
    from retarget.cli import plugins_cmd

    def broken(*_args):
        raise ZeroDivisionError("deep inside")

    monkeypatch.setattr(plugins_cmd, "run_list", broken)
    monkeypatch.delenv("RETARGET_DEBUG", raising=False)
    assert main(["plugins"]) == 1
    err = capsys.readouterr().err
    assert "unexpected failure of 'retarget plugins': ZeroDivisionError: deep inside" in err
    assert "Traceback" not in err
    saved = err.split("traceback is in ")[1].split()[0]
    assert "ZeroDivisionError" in Path(saved).read_text(encoding="utf-8")


@pytest.mark.parametrize(
    ("argv", "extra"),
    [
        (["export", "runs/none/latest", "--onnx"], "export"),
        (["play", "runs/none/latest", "--out", "x.mp4"], "video"),
        (["motion", "show", "clip.bvh", "--out", "x.mp4"], "video"),
    ],
)
def test_missing_extras_are_named_before_any_work(argv, extra, monkeypatch, capsys) -> None:
    import importlib.util

    real = importlib.util.find_spec
    absent = {"onnx", "imageio", "imageio_ffmpeg"}
    monkeypatch.setattr(
        importlib.util, "find_spec", lambda name, *a: None if name in absent else real(name, *a)
    )
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert f"pip install 'retarget[{extra}]'" in err  # not "no run" / "file not found"
    assert "not installed" in err and "Traceback" not in err


def test_every_option_and_argument_of_every_command_has_a_help_line() -> None:
    import argparse

    from retarget.cli.main import build_parser
    from retarget.registry.loader import load_plugins

    silent = []

    def walk(parser: argparse.ArgumentParser, path: list[str]) -> None:
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, sub in action.choices.items():
                    walk(sub, [*path, name])
            elif not action.help and action.dest != "help":
                silent.append(f"{' '.join(path)} {action.dest}")

    walk(build_parser(load_plugins()), ["retarget"])
    assert not silent, silent


@pytest.mark.parametrize("size", ["0x0", "100000x10", "big"])
def test_picture_sizes_are_bounded_before_any_work(size, capsys) -> None:
    with pytest.raises(SystemExit) as info:
        main(["play", "runs/none/latest", "--out", "x.gif", "--size", size])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert "--size" in err and ("16..4096" in err or "WIDTHxHEIGHT" in err)
