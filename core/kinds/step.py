"""What every plugin that runs each control step shares: binding, resets, and what it needs.

Sensors, observers, reward terms and terminations all see a :class:`StepContext`. They
resolve names to indices once (``bind``), forget per-environment state on resets, and say
what the step must gather for them (``needs``; what they require of the character is
the ``requires`` class attribute every plugin has): the environment fills only what some
component asked for, once per step, in typed fields of the context.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from retarget.kinds.base import ConfigT, Plugin, PluginConfig

if TYPE_CHECKING:
    import torch

    from retarget.kinds.lookup import PluginLookup
    from retarget.kinds.state import Layout
    from retarget.motion.library import MotionLibrary


@dataclass(frozen=True)
class StepNeeds:
    """What a step plugin reads beyond the simulated state and the reference pose.

    ``reference_offsets``: frames ``k >= 1`` ahead at which it reads the full reference state
    (``ctx.ref.future[k]``), e.g. a teacher's target body or the critic's privileged
    future. ``scene_contacts``: it reads the reference's scene contact labels
    (``ctx.ref.scene_contacts``).
    """

    reference_offsets: tuple[int, ...] = ()
    scene_contacts: bool = False

    def __or__(self, other: StepNeeds) -> StepNeeds:
        offsets = tuple(sorted({*self.reference_offsets, *other.reference_offsets}))
        return StepNeeds(offsets, self.scene_contacts or other.scene_contacts)


class StepPlugin(Plugin[ConfigT]):
    """Base of the plugins that run every control step, on whole batches of environments."""

    registry: PluginLookup | None = None
    """The invocation's plugins, set by :meth:`connect` when the env is built from a recipe."""

    def connect(self, registry: PluginLookup) -> None:
        """Receive the invocation's plugin registry before :meth:`bind` (kept as
        ``self.registry``), so a plugin that builds other plugins (a sensor wrapping an
        estimator run) resolves them against the same set the recipe was resolved with."""
        self.registry = registry

    def pinned_config(self, registry: PluginLookup) -> PluginConfig | None:
        """The config a new run locks when this one names something that can move (another
        run's ``latest`` checkpoint): fixed to what it is now, so the run's lock says exactly
        what it read and a resume reads the same, as a student's lock names its teacher's
        checkpoint. Errors about what it names are raised here, before anything is built.
        Default: ``None`` (locked as configured)."""
        return None

    def bind(self, layout: Layout) -> None:
        """Resolve names to indices once, before the first step."""

    def reset(self, env_ids: torch.Tensor) -> None:
        """Forget per-environment state of ``env_ids`` (stateless plugins ignore this)."""

    def prepare(self, library: MotionLibrary) -> None:
        """Precompute what depends only on the reference frames, once, before the first step:
        ``library`` holds every clip at the control rate as flat rows (``global_pos``,
        ``global_rot``, ``devices``, ``heights`` per clip, ``start``/``length``), and each step's
        ``ctx.ref.rows`` says which row every environment is at. Default: nothing."""

    def needs(self) -> StepNeeds:
        """What the step must gather for this plugin; the default asks for nothing extra."""
        return StepNeeds()
