"""Characters: a body built procedurally as an ``mujoco.MjSpec`` from the plugin's ``Config``."""

from __future__ import annotations

from abc import abstractmethod
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, ClassVar

from retarget.kinds.base import ConfigT, Plugin

if TYPE_CHECKING:
    import mujoco

    from retarget.character.joint_map import JointMap

REQUIRED_SITES: tuple[str, ...] = ("head", "left_hand", "right_hand", "root")
"""Role sites every character provides: the headset mount, controller mounts and the root."""

REQUIRED_GROUPS: tuple[str, ...] = ("feet", "upper_body")
"""Body groups every character provides: foot contact and fall detection rely on them."""


class Character(Plugin[ConfigT]):
    """Base class of characters.

    A character builds its own MJCF (``build_spec``) with a free root joint first, torque
    actuators with per-joint limits (``forcerange``), and the role sites/body groups that other
    plugins rely on. Passive joints (tails, ears) are springs and dampers with no actuator: they
    are observed but never driven.
    """

    kind: ClassVar[str] = "character"

    @abstractmethod
    def build_spec(self) -> mujoco.MjSpec:
        """Return a fresh, uncompiled spec of the character (root body under the worldbody)."""
        ...

    def site_roles(self) -> Mapping[str, str]:
        """Role name (``head``, ``left_hand``, ...) -> site name in the spec."""
        return {role: role for role in REQUIRED_SITES}

    @abstractmethod
    def body_groups(self) -> Mapping[str, Sequence[str]]:
        """Group name (``feet``, ``upper_body``, ...) -> body names in the spec."""
        ...

    def passive_joints(self) -> Sequence[str]:
        """Joints that are simulated but never actuated (spring-damper only)."""
        return ()

    def joint_weights(self) -> Mapping[str, float]:
        """Per-joint reward weights (missing joints weigh 1.0)."""
        return {}

    def joint_map(self) -> JointMap | None:
        """How human joints drive this character's joints in kinematic retargeting.

        ``None`` (the default) means the character cannot be retargeted kinematically; see
        :mod:`retarget.character.joint_map`.
        """
        return None
