"""The declared toolkit: the retarget modules a plugin may import, and a check that it does.

Everything not listed here is an implementation detail that may change between releases.
Built-in plugins are held to the same list as third-party ones (the contract suite runs
:func:`check_uses_toolkit` on every plugin), so the list is exactly what a plugin needs.
A package entry (one ending in ``.*``) admits the package and its submodules.
"""

from __future__ import annotations

import ast
import inspect
import sys
from collections.abc import Iterable
from pathlib import Path

TOOLKIT: dict[str, str] = {
    "retarget": "the plugin API: base classes, step state, hookimpl, errors (``retarget.__all__``)",
    "retarget.errors": "errors a user can act on",
    "retarget.kinds.*": "the base class of each plugin kind and the step data they see",
    "retarget.character.builder": "procedural MJCF for characters (BodyBuilder and helpers)",
    "retarget.character.joint_map": "which human joints drive which character joints",
    "retarget.character.kinematic": "kinematic retargeting of a clip onto a character",
    "retarget.geometry.heading": "batched torch rotations and the character's heading frame",
    "retarget.geometry.rotations": "numpy quaternions for motion data",
    "retarget.scene.props": "the prop-scene base class (boxes, chairs, couches, ...)",
    "retarget.scene.floor": "the ground plane",
    "retarget.scene.ground": "the floor-only scene every environment has without another",
    "retarget.scene.mesh_boxes": "upright boxes read from a mesh file",
    "retarget.scene.contacts": "the links and force threshold of scene-contact labels",
    "retarget.motion.clip": "MotionClip, what motion formats read and write",
    "retarget.motion.skeleton": "the canonical human skeleton",
    "retarget.motion.procedural": "generated clips (idle, walk) for defaults and tests",
    "retarget.motion.sources": "loading the clips of a path with the registered formats",
    "retarget.motion.import_bvh": "reading BVH into canonical clips",
    "retarget.motion.import_amass": "reading AMASS (SMPL-family .npz) into canonical clips",
    "retarget.motion.amass_write": "writing canonical clips as AMASS-style .npz",
    "retarget.motion.import_positions": "reading position-only captures into canonical clips",
    "retarget.motion.position_layouts": "joint-name layouts of position-only captures",
    "retarget.motion.bvh_write": "writing clips as BVH",
    "retarget.motion.camera_rigs": "headset camera rigs (where the tracking cameras sit)",
    "retarget.motion.scene_fit": "fitting props to where a clip sits and steps",
    "retarget.motion.hinge_elbows": "a clip's elbows rewritten as hinges (its pose unchanged)",
    "retarget.expert.*": "tracking experts (paths, beam search, iLQR refinement) and their files, "
    "for planners and students that learn from them",
    "retarget.learn.*": "building blocks of algorithm plugins (networks, PPO, DAgger, ...)",
    "retarget.env": "the tracking environment (``RetargetEnv``, ``random_actions``)",
    "retarget.env.build": "building an environment from a resolved recipe",
    "retarget.recipe": "reading, resolving and overriding recipes",
    "retarget.settings.*": "the recipe's env and sim settings schemas",
    "retarget.train.load": "loading a trained run (recipe lock, algorithm, weights)",
    "retarget.train.run_dir": "run directories: resolving, latest checkpoint, lock file name",
    "retarget.commands.recipe_args": "the recipe argument and override flags for command plugins",
    "retarget.commands.numbers": "bounded number and picture-size flags for command plugins",
    "retarget.motion.devices": "headset and controller poses synthesised from a clip",
    "retarget.motion.library": "the motion library a step plugin's prepare() reads",
    "retarget.motion.device_recording": "recorded device streams (.jsonl) and conventions",
    "retarget.motion.device_frames": "a recording's camera frames (NAME.frames.npz)",
    "retarget.render.*": "offscreen pictures and videos of characters, clips and rollouts",
    "retarget.testing.*": "the contract suite and its test doubles",
}
"""Module -> what a plugin uses it for."""

PROVISIONAL: frozenset[str] = frozenset({
    "retarget.expert.*",
    "retarget.learn.*",
    "retarget.env",
    "retarget.env.build",
    "retarget.settings.*",
    "retarget.train.load",
    "retarget.train.run_dir",
    "retarget.motion.scene_fit",
    "retarget.motion.library",
    "retarget.motion.device_frames",
    "retarget.render.*",
})
"""Toolkit entries whose names may still change between minor releases (learning building
blocks, the environment, run files, pictures): a plugin may import them, and
:func:`provisional_imports` lists where it does. Every other entry is *stable*: the plugin
base classes, step data, errors, the character builder and joint maps, rotations, prop
scenes, motion clips and readers, recipes and the contract suite change only with a
deprecation first."""


def tier(module: str) -> str | None:
    """``"stable"`` or ``"provisional"`` for a toolkit module, ``None`` outside it."""
    if not allowed(module):
        return None
    for entry in PROVISIONAL:
        package = entry.removesuffix(".*")
        if module == package or (entry.endswith(".*") and module.startswith(package + ".")):
            return "provisional"
    return "stable"


def allowed(module: str) -> bool:
    """Whether ``module`` (dotted) is part of the declared toolkit."""
    for entry in TOOLKIT:
        if entry.endswith(".*"):
            package = entry[:-2]
            if module == package or module.startswith(package + "."):
                return True
        elif module == entry:
            return True
    return False


def _imports(tree: ast.AST) -> Iterable[tuple[int, str]]:
    """(line, module) of every absolute retarget import; ``from pkg import name`` counts as
    ``pkg.name`` when that names a module, else as ``pkg``."""
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            if node.module == "retarget":
                yield node.lineno, "retarget"
                continue
            for alias in node.names:
                sub = f"{node.module}.{alias.name}"
                yield node.lineno, sub if sub in sys.modules or _is_module(sub) else node.module


def _is_module(dotted: str) -> bool:
    import importlib.util

    try:
        return importlib.util.find_spec(dotted) is not None
    except (ImportError, ValueError):
        return False


def toolkit_violations(files: Iterable[Path], own: str) -> list[str]:
    """``path:line module`` for each retarget import in ``files`` that is neither the
    toolkit nor the plugin's own package ``own`` (a dotted prefix)."""
    found = []
    for path in files:
        tree = ast.parse(Path(path).read_text(encoding="utf-8"), filename=str(path))
        for line, module in _imports(tree):
            top = module.split(".")[0]
            if module == own or module.startswith(own + "."):
                continue
            if top == "retarget" and not allowed(module):
                found.append(f"{path}:{line} imports {module}")
    return found


def provisional_imports(files: Iterable[Path]) -> list[str]:
    """``path:line module`` for each import of a provisional toolkit module in ``files``:
    what a plugin package should re-check when it moves to a new retarget release."""
    found = []
    for path in files:
        tree = ast.parse(Path(path).read_text(encoding="utf-8"), filename=str(path))
        found.extend(f"{path}:{line} imports {module}" for line, module in _imports(tree)
                     if tier(module) == "provisional")  # fmt: skip
    return found


def own_package(cls: type) -> str:
    """The package a plugin class ships in: ``retarget.plugins`` for built-ins, else the top
    level package of its module."""
    module = cls.__module__
    for package in ("retarget.plugins", "retarget.testing"):  # built-ins, the suite's doubles
        if module.startswith(package + "."):
            return package
    return module.split(".")[0]


def check_uses_toolkit(plugin: object) -> None:
    """The plugin's module imports only toolkit modules from retarget (beside its own)."""
    cls = plugin if isinstance(plugin, type) else type(plugin)
    source = inspect.getsourcefile(cls)
    if source is None:  # defined interactively: nothing to read
        return
    own = own_package(cls)
    if own == "retarget":
        raise AssertionError(
            f"{cls.__qualname__} lives inside retarget ({cls.__module__}) but outside "
            "retarget.plugins: plugins ship in their own package"
        )
    bad = toolkit_violations([Path(source)], own)
    assert not bad, "imports outside the declared toolkit (retarget.testing.toolkit):\n" + (
        "\n".join(bad)
    )
