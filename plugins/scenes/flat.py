"""``flat``: the floor alone (z = 0), the scene every other scene is built on.

The same floor every environment has when its recipe names no scene
(:class:`retarget.scene.ground.Ground`), under the name recipes use.
"""

from __future__ import annotations

import retarget
from retarget.scene.ground import Ground, GroundConfig

FlatConfig = GroundConfig


class Flat(Ground):
    """An infinite flat floor at z = 0; nothing to randomize.

    The floor has no props, so its surface points are drawn on the floor inside a square of
    half side ``extent`` around the origin (other scenes leave the floor out of their points).
    """

    name = "flat"


@retarget.hookimpl
def register_scenes(register) -> None:
    register(Flat)
