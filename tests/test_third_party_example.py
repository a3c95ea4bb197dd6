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
