"""The type checker reads the public plugin API and the built-in plugins as ``retarget`` does.

The import package ``retarget`` lives in ``core/`` (and ``retarget.plugins`` in ``plugins/``),
mapped by setuptools' ``package-dir``; an editable install reaches it through an import hook
that mypy cannot follow, so a plain ``mypy`` run sees every ``from retarget import ...`` as
``Any`` and checks nothing across modules. This test lays the sources out as installed
(``retarget/`` with ``retarget/plugins/`` inside it) in a temporary folder and runs mypy there
on the files ``[tool.mypy]`` names, so a plugin reading a field its config lacks, or a kind
whose signature a plugin breaks, fails here. Paths in the report are mapped back to the repo.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = sorted(p.parent for p in (ROOT / "examples").glob("third_party_*/src/*/__init__.py"))
"""The example third-party packages: checked as a package outside retarget would be."""


def _python_only(folder: str, names: list[str]) -> set[str]:
    return {n for n in names if not (Path(folder, n).is_dir() or n.endswith(".py"))}


def _laid_out(tmp: Path) -> Path:
    tree = tmp / "tree"
    shutil.copytree(ROOT / "core", tree / "retarget", ignore=_python_only)
    shutil.copytree(ROOT / "plugins", tree / "retarget" / "plugins", ignore=_python_only)
    for package in EXAMPLES:
        shutil.copytree(package, tree / package.name, ignore=_python_only)
    return tree


def _installed_path(repo_path: str) -> str:
    """``core/kinds`` -> ``retarget/kinds``; ``plugins/x`` -> ``retarget/plugins/x``."""
    if repo_path in ("core", "plugins"):
        return "retarget" if repo_path == "core" else "retarget/plugins"
    if repo_path.startswith("core/"):
        return "retarget/" + repo_path[len("core/"):]
    if repo_path.startswith("plugins/"):
        return "retarget/" + repo_path
    raise ValueError(f"[tool.mypy] files must lie in core/ or plugins/: {repo_path}")


def _repo_path(line: str) -> str:
    for package in EXAMPLES:
        if line.startswith(package.name + "/"):
            return str(package.relative_to(ROOT)) + line[len(package.name):]
    if line.startswith("retarget/plugins/"):
        return line[len("retarget/"):]
    if line.startswith("retarget/"):
        return "core/" + line[len("retarget/"):]
    return line


def _ini(config: dict, files: list[str]) -> str:
    """``[tool.mypy]`` of pyproject.toml as a mypy.ini for the laid-out tree."""
    lines = ["[mypy]", "files = " + ", ".join(files), "incremental = False"]
    for key, value in config.items():
        if key == "files":
            continue
        if isinstance(value, list):
            value = ", ".join(value)
        elif isinstance(value, bool):
            value = str(value)
        lines.append(f"{key} = {value}")
    return "\n".join(lines) + "\n"


def _mypy(tree: Path, files: list[str]) -> subprocess.CompletedProcess[str]:
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["mypy"]
    (tree / "mypy.ini").write_text(_ini(config, files))
    return subprocess.run(
        [sys.executable, "-m", "mypy", "--config-file", "mypy.ini"],
        cwd=tree, capture_output=True, text=True, timeout=600,
    )


def test_mypy_on_the_installed_layout(tmp_path: Path) -> None:
    pytest.importorskip("mypy")
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["mypy"]
    tree = _laid_out(tmp_path)
    files = [_installed_path(f) for f in config["files"]] + [p.name for p in EXAMPLES]
    run = _mypy(tree, files)
    report = "\n".join(_repo_path(line) for line in run.stdout.splitlines())
    assert run.returncode == 0, report + run.stderr


def test_the_layout_resolves_retarget(tmp_path: Path) -> None:
    """The check can fail: a plugin reading a field its config lacks is reported."""
    pytest.importorskip("mypy")
    tree = _laid_out(tmp_path)
    bad = tree / "retarget" / "plugins" / "rewards" / "broken.py"
    bad.write_text(
        "from retarget import PluginConfig, StepContext, Termination\n"
        "import torch\n\n\n"
        "class Broken(Termination[PluginConfig]):\n"
        "    name = 'broken'\n\n"
        "    def check(self, ctx: StepContext) -> torch.Tensor:\n"
        "        return self.config.no_such_field\n"
    )
    run = _mypy(tree, [str(bad.relative_to(tree))])
    assert run.returncode != 0 and "no_such_field" in run.stdout, run.stdout + run.stderr
