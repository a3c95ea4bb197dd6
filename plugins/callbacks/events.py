"""``events``: a run's progress as JSON lines, one per event, for a monitor to tail.

The smallest useful logger, and the shape of any other (W&B, MLflow): start, each
iteration's figures, each checkpoint, the end, appended to ``RUN/events.jsonl`` (or the file
``name`` inside the run directory). Non-finite figures are written as ``null`` so every line
is strict JSON.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from pydantic import Field

import retarget


class EventsConfig(retarget.PluginConfig):
    name: str = Field("events.jsonl", pattern=r"^[A-Za-z0-9_.-]{1,64}\.jsonl$",
                      description="file inside the run directory")  # fmt: skip
    every: int = Field(1, ge=1, le=1_000_000, description="write every k-th iteration")


class Events(retarget.Callback[EventsConfig]):
    """Append the run's start, iterations, checkpoints and end to RUN/events.jsonl."""

    name = "events"

    def __init__(self, config: EventsConfig | None = None) -> None:
        super().__init__(config)
        self.file: Path | None = None

    def _write(self, event: str, **fields: Any) -> None:
        if self.file is None:
            return
        row = {"event": event, "time": time.time(), **fields}
        with self.file.open("a", encoding="utf-8") as handle:
            handle.write(json.dumps(row, allow_nan=False) + "\n")

    def on_train_start(self, run: Path, recipe: Mapping[str, Any], resumed: bool) -> None:
        self.file = Path(run) / self.config.name
        self._write("start", run=str(run), resumed=resumed, recipe=dict(recipe))

    def on_iteration(self, iteration: int, env_steps: int, stats: Mapping[str, float]) -> None:
        if iteration % self.config.every:
            return
        clean = {k: (float(v) if math.isfinite(float(v)) else None) for k, v in stats.items()}
        self._write("iteration", iteration=iteration, env_steps=env_steps, stats=clean)

    def on_checkpoint(self, path: Path, iteration: int) -> None:
        self._write("checkpoint", path=str(path), iteration=iteration)

    def on_train_end(self, reason: str, last_checkpoint: Path | None) -> None:
        self._write("end", reason=reason,
                    last_checkpoint=str(last_checkpoint) if last_checkpoint else None)  # fmt: skip


@retarget.hookimpl
def register_callbacks(register) -> None:
    register(Events)
