"""Per-iteration metrics to ``metrics.csv`` and TensorBoard.

The CSV is rewritten with a wider header when a new metric appears (rare: new reward terms
appear after the first finished episode), so every row keeps every column.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Mapping
from pathlib import Path


class MetricsLogger:
    """Appends one row per iteration; ``step`` is the environment step count."""

    def __init__(self, run: Path, tensorboard: bool = True) -> None:
        self.csv_path = run / "metrics.csv"
        self.columns: list[str] = []
        self.rows: list[dict[str, float]] = []
        if self.csv_path.exists():  # resuming: keep the rows written so far
            with self.csv_path.open(newline="") as handle:
                reader = csv.DictReader(handle)
                self.columns = list(reader.fieldnames or [])
                self.rows = [{k: float(v) for k, v in r.items() if v != ""} for r in reader]
        self.writer = None
        if tensorboard:
            try:
                from torch.utils.tensorboard import SummaryWriter
            except ImportError:  # pragma: no cover - tensorboard is a dependency
                self.writer = None
            else:
                self.writer = SummaryWriter(str(run / "tb"))

    def log(self, step: int, metrics: Mapping[str, float]) -> None:
        row = {"step": float(step), **{k: float(v) for k, v in metrics.items()}}
        new = [k for k in row if k not in self.columns]
        self.rows.append(row)
        if new:
            self.columns += new
            self._rewrite()
        else:
            with self.csv_path.open("a", newline="") as handle:
                csv.DictWriter(handle, self.columns).writerow(row)
        if self.writer is not None:
            for key, value in row.items():
                if key != "step" and math.isfinite(value):
                    self.writer.add_scalar(key, value, step)

    def drop_after(self, iteration: int) -> None:
        """Forget rows of iterations after ``iteration``: a run killed between checkpoints
        logged iterations that its resume will redo, and each should appear once."""
        kept = [r for r in self.rows if r.get("iteration", 0.0) <= iteration]
        if len(kept) != len(self.rows):
            self.rows = kept
            self._rewrite()

    def _rewrite(self) -> None:
        tmp = self.csv_path.with_suffix(".csv.tmp")
        with tmp.open("w", newline="") as handle:
            writer = csv.DictWriter(handle, self.columns)
            writer.writeheader()
            writer.writerows(self.rows)
        tmp.replace(self.csv_path)

    def close(self) -> None:
        if self.writer is not None:
            self.writer.flush()
            self.writer.close()
