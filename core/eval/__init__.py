"""Evaluation: the metrics of DESIGN.md §8 for a policy tracking reference motion."""

from __future__ import annotations

from retarget.eval.runner import EvalSettings, evaluate

__all__ = ["EvalSettings", "evaluate"]
