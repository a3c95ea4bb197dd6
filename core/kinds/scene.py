"""Scenes: static and articulated props added to the world, plus batched geometry queries."""

from __future__ import annotations

from abc import abstractmethod
from typing import TYPE_CHECKING, Any, ClassVar

from retarget.kinds.base import ConfigT, Plugin

if TYPE_CHECKING:
    from collections.abc import Mapping, Sequence

    import mujoco
    import numpy as np
    import torch

    from retarget.motion.clip import MotionClip


class Scene(Plugin[ConfigT]):
    """Base class of scenes.

    ``build`` adds geometry to a world spec (the floor is the scene's job too).
    ``height_at`` answers height queries for many points of many environments at once, which
    is what the height-map observer uses instead of per-point ray casts.

    All environments share one compiled model, so a scene whose props move between episodes
    (scene randomization) places them as *mocap bodies*: their poses are per-environment state.
    The environment calls :meth:`allocate` once with its number of environments, then on every
    reset :meth:`randomize` for the reset environments and writes :meth:`mocap_poses` into the
    simulation. Queries then answer for each environment's own placement: ``height_at`` takes
    ``(N, K, 2)`` with ``N`` the allocated environments (or any ``N`` before ``allocate``, at
    the default placement), and :meth:`select` gives the view of a subset.
    """

    kind: ClassVar[str] = "scene"

    @abstractmethod
    def build(self, spec: mujoco.MjSpec) -> None: ...

    @abstractmethod
    def height_at(self, xy: torch.Tensor) -> torch.Tensor:
        """Ground height under world points ``xy`` ``(N, K, 2)`` -> ``(N, K)``."""
        ...

    @abstractmethod
    def surface_points(self, count: int, rng: np.random.Generator) -> np.ndarray:
        """``count`` points sampled on the scene's surfaces, world frame ``(N, count, 3)``.

        ``N`` is the number of allocated environments (1 before :meth:`allocate`, and a
        static scene may always return one row, which holds for every environment); every
        environment gets the same samples on its props, placed where that environment's props
        are, so rows differ only by placement.
        """
        ...

    def local_surface_points(self, count: int, rng: np.random.Generator) -> np.ndarray | None:
        """``count`` samples in the props' own frames ``(count, 4)`` (prop index, x, y, z), for
        scenes whose props move between episodes: an observer draws them once and places them
        with :meth:`place_surface_points` after every reset, instead of sampling anew. None
        (the default): the scene has no such frames; :meth:`surface_points` is used."""
        return None

    def place_surface_points(
        self, local: torch.Tensor, dtype: torch.dtype | None = None
    ) -> torch.Tensor:
        """Place :meth:`local_surface_points` samples for every held environment
        ``(N, count, 3)``; needed only by scenes whose ``local_surface_points`` returns
        samples."""
        raise NotImplementedError(
            f"scene {self.name} returned local surface points but does not place them"
        )

    def fit_motion(self, clips: Sequence[MotionClip]) -> None:
        """Adapt the scene to the run's motion clips before it is built (most scenes ignore
        this; ``motion_props`` places seats and boxes where the motions need them)."""

    def allocate(self, num_envs: int) -> None:
        """Size the per-environment placement state (static scenes ignore this)."""

    def start_episodes(
        self, env_ids: torch.Tensor, clip: torch.Tensor, seconds: torch.Tensor
    ) -> None:
        """Which clip (index into the clips of :meth:`fit_motion`) and time in it (seconds)
        each environment of ``env_ids`` starts its new episode at; called on every reset just
        before :meth:`randomize`, so scenes laid out along the reference motion (``path_boxes``)
        can place props where that episode's motion goes. Most scenes ignore this."""

    def randomize(self, env_ids: torch.Tensor, generator: torch.Generator) -> None:
        """Re-draw per-episode placement noise for ``env_ids`` (static scenes ignore this)."""

    def select(self, env_ids: torch.Tensor) -> Scene[Any]:
        """The scene as seen by environments ``env_ids`` only (static scenes are themselves)."""
        return self

    def state_dict(self) -> dict[str, torch.Tensor]:
        """Per-environment placement state for checkpoints (static scenes have none)."""
        return {}

    def load_state_dict(self, state: Mapping[str, torch.Tensor]) -> None:
        """Restore :meth:`state_dict` (static scenes ignore this)."""

    def reference_placement(self, clip: int) -> tuple[torch.Tensor, torch.Tensor] | None:
        """Positions ``(M, 3)`` and ``wxyz`` quaternions ``(M, 4)`` of the mocap bodies while
        clip ``clip``'s reference is labelled (its scene contacts): a scene whose props
        differ per clip says where they stand for that clip. ``None`` (the default): the
        compiled placement serves every clip."""
        return None

    def mocap_bodies(self) -> tuple[str, ...]:
        """Names of the mocap bodies whose poses :meth:`mocap_poses` gives, in that order."""
        return ()

    def mocap_poses(self, env_ids: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """Positions ``(E, M, 3)`` and ``wxyz`` quaternions ``(E, M, 4)`` of the mocap bodies
        for environments ``env_ids`` (``M = len(mocap_bodies())``)."""
        import torch
        e = int(env_ids.numel())
        quat = torch.zeros(e, 0, 4, dtype=torch.float64)
        return torch.zeros(e, 0, 3, dtype=torch.float64), quat
