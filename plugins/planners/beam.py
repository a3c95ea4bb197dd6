"""``beam``: SAMCON-style sampling beam search over PD targets (:mod:`retarget.expert.beam`)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import retarget
from retarget import Planner, Track
from retarget.expert.config import ExpertConfig


class BeamPlanner(Planner[ExpertConfig]):
    """Sampling beam search over PD-target offsets around the reference (SAMCON-style).

    It keeps the best states after every short segment, so a doomed state is outrun by
    others; ``retarget.expert.config.ExpertConfig`` documents every setting."""

    name = "beam"

    @classmethod
    def example(cls) -> BeamPlanner:
        return cls(ExpertConfig(samples=24, beam=4, keep=2))

    def track(
        self,
        env: Any,
        clip: int,
        *,
        seconds: float | None = None,
        threads: int = 1,
        progress: Callable[[int], None] | None = None,
    ) -> Track:
        from retarget.expert.beam import BeamTracker

        return BeamTracker(env, self.config, threads=threads).track(clip, seconds, progress)


@retarget.hookimpl
def register_planners(register) -> None:
    register(BeamPlanner)
