"""Training callbacks: what a logger (W&B, MLflow, a dashboard) hooks into.

A callback is named in a recipe's ``callbacks`` list and told about the run as it goes: its
start (run directory and the resolved recipe as plain data), every iteration (counters and
the iteration's statistics, the same numbers as ``metrics.csv``), every checkpoint written,
and the end. It only observes: the statistics it gets are a read-only copy, and a callback
that raises is switched off for the rest of the run with a warning naming it, so a logging
service that is down never costs a training run.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any, ClassVar

from retarget.kinds.base import ConfigT, Plugin


class Callback(Plugin[ConfigT]):
    """Base class of training callbacks; every method is optional (the defaults do nothing).

    Only the main process of a data-parallel run calls them (rank 0, the one that writes
    checkpoints), so a logger sees each iteration once.
    """

    kind: ClassVar[str] = "callback"

    def on_train_start(self, run: Path, recipe: Mapping[str, Any], resumed: bool) -> None:
        """The run directory, the resolved recipe (JSON-ready) and whether it resumes."""

    def on_iteration(self, iteration: int, env_steps: int, stats: Mapping[str, float]) -> None:
        """After each training iteration: ``stats`` holds the iteration's figures
        (losses, returns, ``elapsed_s``, ``steps_per_s_total``, ...)."""

    def on_checkpoint(self, path: Path, iteration: int) -> None:
        """After a checkpoint file is written (atomically: it is complete when this runs)."""

    def on_train_end(self, reason: str, last_checkpoint: Path | None) -> None:
        """Once, when training stops: ``reason`` is ``budget``, ``interrupted`` or ``error``."""
