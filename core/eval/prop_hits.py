"""Feet hitting props: which simulated feet touch a scene prop, on its top or against a side.

The boxes-on-a-flat-path check (QuestEnvSim Fig. 5) asks whether a policy that sees the boxes
lifts its feet over them. From MuJoCo's contact list, a step counts as a *top* step when a
foot geom pushes on a prop geom (normal force above ``newtons``) through a mostly vertical
contact normal (``|n_z| >= cos 45 deg``: stepping onto the box), and as a *side* hit when the
normal is mostly horizontal (the foot runs into the box's side: a stumble). Props are the
geoms of mocap bodies and of bodies hinged to them (:mod:`retarget.scene.props`);
the floor and the character's other bodies never count.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from retarget.kinds.state import Layout

HIT_NEWTONS = 1.0
"""Normal force above which a foot-prop contact counts."""

VERTICAL = math.cos(math.radians(45.0))
"""``|n_z|`` at or above which a contact normal counts as vertical (a box top)."""


def foot_geoms(model: mujoco.MjModel, layout: Layout) -> np.ndarray:
    """``(ngeom,)`` bool: geoms of the character's feet (``left_foot``/``right_foot`` body
    groups, else ``feet``); raises naming the character's groups when it has none."""
    groups = layout.body_groups
    names = [g for g in ("left_foot", "right_foot") if g in groups] or (
        ["feet"] if "feet" in groups else []
    )
    if not names:
        raise KeyError(f"no foot body group among {sorted(groups)} (want left_foot/right_foot)")
    bodies = [layout.body_ids[i] for g in names for i in groups[g]]
    return np.isin(model.geom_bodyid, bodies)


def prop_geoms(model: mujoco.MjModel) -> np.ndarray:
    """``(ngeom,)`` bool: geoms of mocap bodies and of the bodies below them (scene props)."""
    root = model.body_rootid[model.geom_bodyid]
    return model.body_mocapid[root] >= 0


def foot_prop_contacts(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    feet: np.ndarray,
    props: np.ndarray,
    newtons: float = HIT_NEWTONS,
) -> list[tuple[int, bool]]:
    """``(prop geom id, on top)`` of each foot-prop contact pushing harder than ``newtons``."""
    n = data.ncon
    if n == 0:
        return []
    geom = np.asarray(data.contact.geom[:n]).reshape(-1, 2)
    pair = (feet[geom[:, 0]] & props[geom[:, 1]]) | (props[geom[:, 0]] & feet[geom[:, 1]])
    found = []
    force = np.zeros(6)
    for i in np.nonzero(pair)[0]:  # the few foot-prop contacts only
        mujoco.mj_contactForce(model, data, int(i), force)
        if force[0] <= newtons:  # normal force, contact frame
            continue
        prop = int(geom[i, 1] if props[geom[i, 1]] else geom[i, 0])
        found.append((prop, abs(float(data.contact.frame[i][2])) >= VERTICAL))
    return found


def foot_prop_hits(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    feet: np.ndarray,
    props: np.ndarray,
    newtons: float = HIT_NEWTONS,
) -> tuple[bool, bool]:
    """``(top, side)`` of one simulation's current contacts (see the module doc)."""
    tops = [top for _, top in foot_prop_contacts(model, data, feet, props, newtons)]
    return any(tops), not all(tops)
