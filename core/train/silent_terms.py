"""Reward kernels that give a policy nothing to learn from.

A kernel term ``exp(-k * d)`` (every reward whose config has a ``k``) rewards moving toward
the reference only where its slope is not flat. When ``k`` is too large for the distances a
character produces, the term sits near 0 for every sample and PPO gets no gradient from it:
it still costs compute and looks, in a recipe, as if it mattered. A ``reduce: sum`` over many
joints or bodies makes this easy to do unawares: the human teacher's ``joint_pos`` (``k=25``,
a sum over 35 hinges) averages about 0.0004, and a new character with more joints or a larger
body is further out still. The trainer reports such terms once, early in a run, with the
measured average, so a researcher sees it before hours are spent.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

SILENT_BELOW = 0.01
"""A kernel averaging under this is flat where the policy is (exp(-4.6) and beyond)."""

CHECK_AFTER_ITERATIONS = 10
"""Iterations of a run's process before its terms are judged (enough steps to average)."""


def silent_kernels(terms: Mapping[str, Any], means: Mapping[str, float]) -> list[str]:
    """One line per kernel term whose average value is under :data:`SILENT_BELOW`.

    ``terms`` maps recipe names to reward terms (their ``config`` is read for ``k`` and
    ``reduce``); ``means`` their unweighted averages (``RewardManager.mean_values``).
    """
    lines = []
    for name, mean in means.items():
        config = terms[name].config
        k = getattr(config, "k", None)
        if not isinstance(k, (int, float)) or mean >= SILENT_BELOW:
            continue
        hint = "a smaller k"
        if getattr(config, "reduce", None) == "sum":
            hint += " or `reduce: mean`"
        lines.append(f"rewards.{name}: averages {mean:.4f} (k={k:g}): nearly always 0, so it "
                     f"gives no gradient; try {hint}")
    return lines
