"""``beam_ilqr``: the beam search's path refined by iLQR (:mod:`retarget.expert.ilqr`)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from pydantic import Field

import retarget
from retarget import Planner, PluginConfig, Track
from retarget.expert.config import ExpertConfig, IlqrConfig


class BeamIlqrConfig(PluginConfig):
    """The beam search's settings and the refinement's (``--planner beam.samples=256
    --planner ilqr.iterations=8``)."""

    beam: ExpertConfig = Field(default_factory=ExpertConfig,
                               description="the beam search (as the `beam` planner's settings)")
    ilqr: IlqrConfig = Field(default_factory=IlqrConfig,
                             description="the refinement (retarget.expert.ilqr.IlqrConfig)")


class BeamIlqrPlanner(Planner[BeamIlqrConfig]):
    """The beam search's path, refined by iLQR on the env's own dynamics.

    The beam finds a path that stays up; iLQR with finite-difference derivatives of the env's
    control step then brings its poses closer to the reference. A round is kept only when
    the simulated cost falls, so it never ends worse than the beam's path."""

    name = "beam_ilqr"

    @classmethod
    def example(cls) -> BeamIlqrPlanner:
        return cls(BeamIlqrConfig(beam=ExpertConfig(samples=24, beam=4, keep=2),
                                  ilqr=IlqrConfig(iterations=1, chunk=2)))  # fmt: skip

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
        from retarget.expert.ilqr import IlqrRefiner

        path = BeamTracker(env, self.config.beam, threads=threads).track(clip, seconds, progress)
        return IlqrRefiner(env, self.config.ilqr, threads=threads).refine(clip, path, progress)


@retarget.hookimpl
def register_planners(register) -> None:
    register(BeamIlqrPlanner)
