"""The simulator a recipe asks for: ``sim.backend`` names the engine behind ``BatchedSim``."""

from __future__ import annotations

import mujoco

from retarget.kinds.state import Layout
from retarget.settings.sim import SimSettings
from retarget.sim.batched import BatchedSim


def make_sim(
    model: mujoco.MjModel, layout: Layout, num_envs: int, settings: SimSettings
) -> BatchedSim:
    """``num_envs`` worlds of ``model`` on the engine ``settings.backend`` names: MuJoCo's C
    engine (``mujoco``) or MuJoCo Warp (``warp``, imported only when asked for)."""
    if settings.backend == "warp":
        from retarget.sim.warp_backend import WarpSim

        return WarpSim(model, layout, num_envs, settings)
    return BatchedSim(model, layout, num_envs, settings)
