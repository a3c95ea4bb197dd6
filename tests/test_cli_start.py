"""The CLI's quick verbs do not import the heavy libraries (torch, MuJoCo, numpy).

Timings live in ``benchmarks/cli_start.py``; this checks the property that makes them fast,
which does not depend on how loaded the machine is.
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

HEAVY = ("torch", "mujoco", "numpy", "rich")

_PROBE = """
import json, sys
sys.argv = ["retarget", *sys.argv[1:]]
from retarget.cli.main import main
try:
    main(sys.argv[1:])
except SystemExit:
    pass
print(json.dumps({m: m in sys.modules for m in %r}), file=sys.stderr)
"""


def _imported(*argv: str) -> dict[str, bool]:
    done = subprocess.run(
        [sys.executable, "-c", _PROBE % (HEAVY,), *argv],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    return json.loads(done.stderr.strip().splitlines()[-1])


@pytest.mark.parametrize("argv", [("--help",), ("--version",)])
def test_help_and_version_import_nothing_heavy(argv) -> None:
    loaded = _imported(*argv)
    assert not any(loaded.values()), f"retarget {' '.join(argv)} imported {loaded}"


def test_plugins_listing_imports_neither_torch_nor_mujoco() -> None:
    loaded = _imported("plugins")
    assert not loaded["torch"] and not loaded["mujoco"], loaded
