"""How long the CLI takes to start: ``--version``, ``--help`` and ``plugins``.

Run: ``.venv/bin/python benchmarks/cli_start.py [--repeat 7] [--rev GIT_REV]``

Each command runs ``--repeat`` times as a fresh process (after one warm-up run that fills the
bytecode cache, as on a user's machine); the median wall time is printed beside ``python -c
pass`` measured in the same run, and the ratio to it. ``--rev`` measures another revision of
this repository the same way, in the same run (exported with ``git archive`` into a temporary
package on ``PYTHONPATH``, which takes precedence over the editable install), so before/after
figures share the machine's load. Targets: ``--help`` <= 0.3 s, ``plugins`` <= 1.5 s.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
COMMANDS = {"--version": ["--version"], "--help": ["--help"], "plugins": ["plugins"]}
ENTRY = "import sys; from retarget.cli.main import main; sys.exit(main(sys.argv[1:]))"


def _median_seconds(argv: list[str], env: dict[str, str], repeat: int) -> float:
    subprocess.run(argv, env=env, capture_output=True, check=False)  # warm the bytecode cache
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        subprocess.run(argv, env=env, capture_output=True, check=False)
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def _export(rev: str, into: Path) -> Path:
    """``rev``'s ``core/`` as package ``retarget`` with ``plugins/`` inside it."""
    archive = into / "src.tar"
    with archive.open("wb") as fh:
        subprocess.run(["git", "-C", str(REPO), "archive", rev], stdout=fh, check=True)
    src = into / "src"
    with tarfile.open(archive) as tar:
        tar.extractall(src, filter="data")
    package = into / "pkg" / "retarget"
    shutil.copytree(src / "core", package)
    shutil.copytree(src / "plugins", package / "plugins")
    return into / "pkg"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--rev", help="also measure this git revision (e.g. a commit before)")
    args = parser.parse_args()
    cache = tempfile.mkdtemp(prefix="retarget-pyc-")
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env["PYTHONPYCACHEPREFIX"] = cache
    trees: dict[str, dict[str, str]] = {"this checkout": env}
    tmp = None
    if args.rev:
        tmp = Path(tempfile.mkdtemp(prefix="retarget-rev-"))
        trees[args.rev] = {**env, "PYTHONPATH": str(_export(args.rev, tmp))}
    try:
        base = _median_seconds([sys.executable, "-c", "pass"], env, args.repeat)
        print(f"python -c pass: {base:.3f} s (median of {args.repeat})")
        print(f"{'tree':<16} {'command':<10} {'median s':>9} {'x python':>9}")
        for tree, tree_env in trees.items():
            for name, argv in COMMANDS.items():
                command = [sys.executable, "-c", ENTRY, *argv]
                seconds = _median_seconds(command, tree_env, args.repeat)
                print(f"{tree:<16} {name:<10} {seconds:>9.3f} {seconds / base:>9.1f}")
    finally:
        shutil.rmtree(cache, ignore_errors=True)
        if tmp is not None:
            shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
