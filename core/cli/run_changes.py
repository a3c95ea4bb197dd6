"""``--scene`` / ``--set`` for commands that load a finished run (``play``, ``eval``).

A trained policy can be watched or measured in another scene than the one it was trained in
(a chair instead of the fitted seat, boxes on the path): the run's locked recipe is changed
before it is resolved, exactly as ``retarget train`` changes a recipe, so errors name the flag.
Changes to what the policy observes are refused when the checkpoint is loaded.
"""

from __future__ import annotations

import argparse

from retarget.commands.recipe_args import add_set_flag


def add_run_change_args(parser: argparse.ArgumentParser) -> None:
    """The two flags, with the same meaning as on ``retarget train``."""
    parser.add_argument("--scene", help="replace the run's scene plugin, e.g. chair")
    add_set_flag(parser, "change a field of the run's recipe, e.g. --set scene.position=[-0.3,0]")
