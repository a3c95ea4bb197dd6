"""``retarget motion``: inspect and render motion clips."""

from __future__ import annotations

import argparse

import retarget
from retarget import Command


class MotionCommand(Command):
    """Inspect motion files (table of clip facts) and render them to images."""

    name = "motion"
    help = "inspect and render motion clips"

    def add_arguments(self, parser: argparse.ArgumentParser) -> None:
        parser.add_argument("action", choices=("inspect", "show"))

    def run(self, args: argparse.Namespace) -> int:
        return 0


@retarget.hookimpl
def register_commands(register) -> None:
    register(MotionCommand)
