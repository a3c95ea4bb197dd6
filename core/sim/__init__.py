"""Batched physics: N MuJoCo worlds stepped together, the only place that loops over envs."""

from __future__ import annotations

from retarget.sim.actuation import apply_actuation, describe_actuation
from retarget.sim.batched import BatchedSim, SimSettings

__all__ = ["BatchedSim", "SimSettings", "apply_actuation", "describe_actuation"]
