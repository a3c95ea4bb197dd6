"""The example external package installs, is listed, and its own tests pass outside the repo."""

from __future__ import annotations

import importlib.util
import json
import shutil
import subprocess
import sys
from pathlib import Path

from helpers import REPO

from retarget.cli.main import main

EXAMPLE = REPO / "examples" / "third_party_plugin"
INSTALL_HINT = f"install it first: pip install -e {EXAMPLE.relative_to(REPO)}"


def test_example_is_installed_and_listed(capsys) -> None:
    assert importlib.util.find_spec("retarget_head_height") is not None, INSTALL_HINT
    assert main(["plugins", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    row = next(r for r in rows if r["name"] == "head_height")
    assert (row["kind"], row["distribution"]) == ("reward", "retarget-head-height")


def test_example_suite_passes_from_outside_the_repo(tmp_path: Path) -> None:
    assert importlib.util.find_spec("retarget_head_height") is not None, INSTALL_HINT
    shutil.copytree(EXAMPLE / "tests", tmp_path / "tests")
    result = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "tests"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        check=False,
    )
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-2000:]
    assert " passed" in result.stdout


CREATURE = REPO / "examples" / "third_party_creature"
CREATURE_HINT = f"install it first: pip install -e {CREATURE.relative_to(REPO)}"


def test_character_and_sensor_package_is_listed_and_its_kit_passes(tmp_path: Path,
                                                                    capsys) -> None:  # fmt: skip
    assert importlib.util.find_spec("retarget_boxbot") is not None, CREATURE_HINT
    assert main(["plugins", "--json"]) == 0
    rows = {r["name"]: r for r in json.loads(capsys.readouterr().out)}
    assert (rows["boxbot"]["kind"], rows["boxbot"]["distribution"]) == ("character",
                                                                        "retarget-boxbot")
    assert rows["head_velocity"]["kind"] == "sensor"
    shutil.copytree(CREATURE / "tests", tmp_path / "tests")
    result = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                             "tests"], cwd=tmp_path, capture_output=True, text=True,
                            check=False)  # fmt: skip
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-2000:]
    assert "28 passed" in result.stdout


def test_the_third_party_character_and_sensor_train(tmp_path: Path, monkeypatch) -> None:
    assert importlib.util.find_spec("retarget_boxbot") is not None, CREATURE_HINT
    monkeypatch.chdir(tmp_path)
    assert main(["train", "--character", "boxbot", "--sensors", "hmd,head_velocity",
                 "--steps", "256", "--num-envs", "4", "--threads", "1",
                 "--no-tensorboard"]) == 0  # fmt: skip
    run = (tmp_path / "runs" / "boxbot-hmd-head_velocity" / "latest").resolve()
    assert list((run / "checkpoints").glob("ckpt-*.pt"))
    lock = (run / "recipe.lock.yaml").read_text()
    assert "boxbot" in lock and "head_velocity" in lock
