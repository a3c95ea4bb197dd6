"""The ground every world stands on, added by the world builder and by scenes that own it."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import mujoco


def add_floor(spec: mujoco.MjSpec, size: float = 50.0) -> None:
    """A plane at z = 0 that collides with everything (contype/conaffinity 1)."""
    import mujoco
    spec.worldbody.add_geom(
        name="floor",
        type=mujoco.mjtGeom.mjGEOM_PLANE,
        size=[size, size, 0.1],
        contype=1,
        conaffinity=1,
        rgba=[0.8, 0.8, 0.8, 1.0],
    )
