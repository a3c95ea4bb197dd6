"""What the built-in characters share: a config base and a ``Character`` built with BodyBuilder.

Only public API is used here (``retarget.character.builder``, ``retarget.character.joint_map``,
``retarget.motion.skeleton``), so a third-party character package can copy this pattern.
"""

from __future__ import annotations

from abc import abstractmethod
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any, ClassVar

from pydantic import Field
from typing_extensions import TypeVar

from retarget import Character, PluginConfig, RecipeError
from retarget.character.joint_map import JointMap

if TYPE_CHECKING:
    import mujoco

    from retarget.character.builder import BodyBuilder, BuiltCharacter


class CharacterConfig(PluginConfig):
    """Fields every built-in character has; defaults are the paper's Table 1 per character."""

    height: float = Field(1.75, gt=0.1, le=10.0, description="standing height, floor to crown, m")
    mass: float | None = Field(
        70.0, gt=0.1, le=2000.0,
        description="total mass, kg (uniform density is solved for); None: the character's "
        "own default")
    max_torque: float = Field(300.0, gt=0.0, description="torque limit before per-joint scales")
    joint_map: dict[str, dict[str, Any] | None] = Field(
        default_factory=dict,
        description="overrides of the default joint map: character joint -> "
                    "{human, axes, scale, offset} (merged) or null (unmapped)")


CharacterConfigT = TypeVar("CharacterConfigT", bound=CharacterConfig, default=CharacterConfig)


class ProceduralCharacter(Character[CharacterConfigT]):
    """A character described by a :class:`BodyBuilder`; builds once, hands out copies.

    Subclasses implement ``describe`` (the bodies), ``default_joint_map`` and ``body_groups``,
    and list their lower-body joints (weighted by ``lower_body_weight`` in imitation rewards).
    """

    lower_body_joints: ClassVar[tuple[str, ...]] = ()
    lower_body_weight: ClassVar[float] = 1.0

    def __init__(self, config: PluginConfig | None = None) -> None:
        super().__init__(config)
        self._built: BuiltCharacter | None = None

    @abstractmethod
    def describe(self) -> BodyBuilder:
        """The character's bodies, joints and sites for the current config."""

    @abstractmethod
    def default_joint_map(self) -> JointMap:
        """The hand-made pairing of human and character joints."""

    @property
    def target_mass(self) -> float:
        """Total mass the uniform density is solved for: the config's ``mass``, else the
        default of the base config (characters that scale it with height override this)."""
        mass = self.config.mass
        if mass is None:
            mass = CharacterConfig.model_fields["mass"].default
        return float(mass)

    def built(self) -> BuiltCharacter:
        """The built spec and its facts (density, mass, height, joints), built once."""
        if self._built is None:
            self._built = self.describe().build(mass=self.target_mass)
        return self._built

    def build_spec(self) -> mujoco.MjSpec:
        return self.built().spec.copy()

    def character_joints(self) -> Mapping[str, Sequence[str]]:
        """Character joint -> axes of its hinges (what a joint map is validated against)."""
        return {name: info.axes for name, info in self.built().joints.items()}

    def passive_joints(self) -> Sequence[str]:
        return self.built().passive_hinges()

    def joint_weights(self) -> Mapping[str, float]:
        """Passive joints 0 (never imitated), lower body ``lower_body_weight`` (App. A), else 1."""
        weights: dict[str, float] = {}
        for name, info in self.built().joints.items():
            if info.passive:
                w = 0.0
            elif name in self.lower_body_joints:
                w = self.lower_body_weight
            else:
                w = self.unmapped_weight(name)
            for h in info.hinges:
                weights[h] = w
        return weights

    def unmapped_weight(self, joint: str) -> float:
        """Weight of an active joint that is not lower body (tails override this)."""
        return 1.0

    def joint_map(self) -> JointMap:
        """Default map with the config's overrides, validated against both skeletons."""
        from retarget.motion import skeleton as sk
        try:
            jmap = self.default_joint_map().with_overrides(self.config.joint_map)
        except RecipeError as exc:
            exc.plugin = self.name
            raise
        passive = [n for n, i in self.built().joints.items() if i.passive]
        jmap.validate_against(sk.JOINT_NAMES, self.character_joints(), passive=passive,
                              plugin=self.name)
        return jmap


def scaled(v: Sequence[float], s: float) -> tuple[float, float, float]:
    """A 3-vector times a scale (geometry is written at a reference size, then scaled)."""
    return (v[0] * s, v[1] * s, v[2] * s)
