"""Typed base classes, one per plugin kind. Behaviour lives here; hooks only register."""

from __future__ import annotations

from retarget.kinds.algorithm import Algorithm, VecEnv
from retarget.kinds.base import ConfigT, Plugin, PluginConfig
from retarget.kinds.callback import Callback
from retarget.kinds.character import REQUIRED_GROUPS, REQUIRED_SITES, Character
from retarget.kinds.command import Command
from retarget.kinds.iteration import IterationResult
from retarget.kinds.motion_format import MotionFormat
from retarget.kinds.planner import Planner
from retarget.kinds.reward import RewardConfig, RewardTerm, gaussian_kernel
from retarget.kinds.scene import Scene
from retarget.kinds.sensor import Observer, ObsSpec, RecordedStream, Sensor
from retarget.kinds.step import StepNeeds, StepPlugin
from retarget.kinds.termination import Termination
from retarget.kinds.track import Track
from retarget.kinds.tracking_env import TrackingEnv

KINDS: dict[str, type[Plugin]] = {
    "character": Character,
    "sensor": Sensor,
    "observer": Observer,
    "scene": Scene,
    "reward": RewardTerm,
    "termination": Termination,
    "algorithm": Algorithm,
    "motion_format": MotionFormat,
    "command": Command,
    "callback": Callback,
    "planner": Planner,
}
"""Kind name -> base class. The registry, recipes and contract suite are all keyed by these."""

__all__ = [
    "KINDS",
    "REQUIRED_GROUPS",
    "REQUIRED_SITES",
    "Algorithm",
    "Callback",
    "Character",
    "Command",
    "ConfigT",
    "IterationResult",
    "MotionFormat",
    "ObsSpec",
    "Observer",
    "Planner",
    "Plugin",
    "PluginConfig",
    "RecordedStream",
    "RewardConfig",
    "RewardTerm",
    "Scene",
    "Sensor",
    "StepNeeds",
    "StepPlugin",
    "Termination",
    "Track",
    "TrackingEnv",
    "VecEnv",
    "gaussian_kernel",
]
