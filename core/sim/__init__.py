"""Batched physics: N MuJoCo worlds stepped together, the only place that loops over envs."""

from __future__ import annotations

from typing import TYPE_CHECKING

from retarget.lazy import lazy_exports

if TYPE_CHECKING:
    from retarget.settings.sim import SimSettings
    from retarget.sim.actuation import apply_actuation, describe_actuation
    from retarget.sim.backend import make_sim
    from retarget.sim.batched import BatchedSim

__getattr__ = lazy_exports(
    __name__,
    {
        "apply_actuation": "retarget.sim.actuation",
        "describe_actuation": "retarget.sim.actuation",
        "BatchedSim": "retarget.sim.batched",
        "make_sim": "retarget.sim.backend",
        "SimSettings": "retarget.settings.sim",
    },
)

__all__ = ["BatchedSim", "SimSettings", "apply_actuation", "describe_actuation", "make_sim"]
