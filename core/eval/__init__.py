"""Evaluation: the metrics of DESIGN.md §8 for a policy tracking reference motion."""

from __future__ import annotations

from typing import TYPE_CHECKING

from retarget.lazy import lazy_exports

if TYPE_CHECKING:
    from retarget.eval.runner import EvalSettings, evaluate

__getattr__ = lazy_exports(
    __name__,
    {
        "EvalSettings": "retarget.eval.runner",
        "evaluate": "retarget.eval.runner",
    },
)

__all__ = ["EvalSettings", "evaluate"]
