"""retarget: drive physically simulated avatars of any body shape from VR headset signals.

The public API: ``hookimpl`` for plugin modules, the plugin base classes, the plugin loader and
the step data structures. Plugins may also import the toolkit modules declared in
:data:`retarget.testing.toolkit.TOOLKIT` (character builder, joint maps, rotations, the
prop-scene base, ...); everything else is an implementation detail.
"""

from __future__ import annotations

from retarget.errors import MotionError, PluginError, RecipeError, RetargetError, SimulationError
from retarget.kinds import (
    Algorithm,
    Callback,
    Character,
    Command,
    ConfigT,
    IterationResult,
    MotionFormat,
    Observer,
    ObsSpec,
    Planner,
    Plugin,
    PluginConfig,
    RecordedStream,
    RewardConfig,
    RewardTerm,
    Scene,
    Sensor,
    StepNeeds,
    Termination,
    Track,
    TrackingEnv,
    VecEnv,
    gaussian_kernel,
)
from retarget.kinds.state import Layout, ReferenceBatch, SimState, StepContext
from retarget.registry.hookspecs import hookimpl
from retarget.registry.loader import load_plugins

__version__ = "0.1.0"

__all__ = [
    "Algorithm",
    "Callback",
    "Character",
    "Command",
    "ConfigT",
    "IterationResult",
    "Layout",
    "MotionError",
    "MotionFormat",
    "ObsSpec",
    "Observer",
    "Planner",
    "Plugin",
    "PluginConfig",
    "PluginError",
    "RecipeError",
    "RecordedStream",
    "ReferenceBatch",
    "RetargetError",
    "RewardConfig",
    "RewardTerm",
    "Scene",
    "Sensor",
    "SimState",
    "SimulationError",
    "StepContext",
    "StepNeeds",
    "Termination",
    "Track",
    "TrackingEnv",
    "VecEnv",
    "__version__",
    "gaussian_kernel",
    "hookimpl",
    "load_plugins",
]
