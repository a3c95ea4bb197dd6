"""Shared bits of the character tests: the four built-ins, a floor world, the shared clips."""

from __future__ import annotations

import warnings
from pathlib import Path

import mujoco

from retarget.plugins.characters.dino import Dino
from retarget.plugins.characters.human import Human
from retarget.plugins.characters.jesse import Jesse
from retarget.plugins.characters.oppy import Oppy

CHARACTERS = (Human, Jesse, Dino, Oppy)
MOCAP = Path("/work/shared/data/mocap")

# Paper Table 1 (human: QuestEnvSim's avatar, scaled to 1.75 m at a BMI of 22.9).
TABLE1 = {
    "human": {"mass": 70.13, "height": 1.75, "links": 18, "dof": 32},
    "jesse": {"mass": 60.0, "height": 1.80, "links": 16, "dof": 32},
    "dino": {"mass": 180.0, "height": 2.50, "links": 30, "dof": 44},
    "oppy": {"mass": 7.0, "height": 0.80, "links": 24, "dof": 58},
}
# What we build (DoF differ from the paper where documented in the character's docstring).
BUILT_DOF = {"human": 35, "jesse": 32, "dino": 56, "oppy": 58}


def floor_world(character_spec: mujoco.MjSpec) -> mujoco.MjModel:
    """The character on a plane with ``contype=conaffinity=1`` (the scene convention)."""
    world = mujoco.MjSpec()
    world.option.timestep = character_spec.option.timestep
    world.option.integrator = character_spec.option.integrator
    world.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 1], contype=1,
                             conaffinity=1)
    world.attach(character_spec, prefix="", frame=world.worldbody.add_frame())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # "empty prefix" notice: names stay unprefixed on purpose
        return world.compile()


def clips() -> list[Path]:
    return sorted(MOCAP.glob("*.bvh"))
