"""Behaviour cloning from a tracking expert as an algorithm plugin.

``retarget train --sensors three_point --expert DIR`` (``algorithm: {type: expert_bc,
expert: DIR}``): before the run starts, :meth:`ExpertBC.prepare_recipe` reads
``DIR/expert.json`` and gives the run the expert's clips (``DIR/motions``), scene and physics
(control rate, substeps, PD actuation and gains: the expert's actions mean nothing under
other physics); another character is refused. The student's own sensors stay as the recipe
says, so the locked recipe states exactly what ran and the run evaluates, resumes and exports
without the expert directory's planner.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import retarget
from retarget import IterationResult, PluginError, RecipeError, VecEnv
from retarget.kinds.tracking_env import tracking_env
from retarget.learn.config import ExpertBCConfig
from retarget.learn.delegating import LearnerAlgorithm
from retarget.settings.sim import ACTION_PHYSICS

if TYPE_CHECKING:
    import torch

    from retarget.learn.expert_bc import ExpertBCLearner

PHYSICS = ACTION_PHYSICS
"""Simulation settings the expert's actions depend on: the student takes the expert's."""


class ExpertBC(LearnerAlgorithm[ExpertBCConfig]):
    """A student learns a tracking expert's actions on the expert's replayed states."""

    name = "expert_bc"
    learns_from_reward = False

    def __init__(self, config: ExpertBCConfig | None = None, windows: Any = None) -> None:
        """``windows``: replay these ``ExpertWindows`` instead of the configured directory
        (tests, the contract suite's example)."""
        super().__init__(config)
        self.learner: ExpertBCLearner | None = None
        self._windows = windows

    @classmethod
    def example(cls) -> ExpertBC:
        """Replays a synthetic expert of zero actions (no directory): an environment without
        ``place_state`` is stepped from wherever it is."""
        import numpy as np

        from retarget.learn.expert_bc import ExpertWindows

        def windows(action_dim: int) -> ExpertWindows:
            clip: dict[str, np.ndarray] = {"qpos": np.zeros((10, 1)), "qvel": np.zeros((10, 1)),
                    "actions": np.zeros((9, action_dim), np.float32),
                    "demo_frame": np.zeros(0, int)}  # fmt: skip
            return ExpertWindows([clip], ())

        return cls(ExpertBCConfig(expert="example", rollout_steps=8, minibatch_size=16),
                   windows=windows)  # fmt: skip

    def prepare_recipe(self, recipe: dict[str, Any], registry: Any) -> dict[str, Any]:
        from retarget.expert.store import read_header
        from retarget.train.load import fill_before_fields
        c = self.config
        root = Path(c.expert).resolve()
        header = read_header(root)
        theirs = header["recipe"]

        def kind(r: Mapping[str, Any]) -> Any:
            ch = r.get("character")
            return ch.get("type") if isinstance(ch, dict) else ch

        if kind(recipe) != kind(theirs):
            raise RecipeError(
                f"the expert planned character {kind(theirs)!r}, this recipe has "
                f"{kind(recipe)!r}", file=str(root / "expert.json"), field="character",
                hint=f"--character {kind(theirs)}",
            )
        recipe = dict(recipe)
        recipe["character"] = theirs["character"]
        recipe["scene"] = theirs.get("scene")
        sim = dict(recipe.get("sim") or {})
        for key in PHYSICS:
            if key in (theirs.get("sim") or {}):
                sim[key] = theirs["sim"][key]
        recipe["sim"] = sim
        # the clips as the expert read them (level feet, rest ends), from its own copies
        recorded = {"motions": dict(theirs.get("motions") or {})}
        fill_before_fields(recorded)  # an expert planned before a field existed
        recipe["motions"] = {**recorded["motions"], "path": str(root / "motions"),
                             "include": [], "exclude": []}  # fmt: skip
        algorithm = dict(recipe["algorithm"])
        algorithm["expert"] = str(root)
        recipe["algorithm"] = algorithm
        return recipe

    def setup(self, env: VecEnv, generator: torch.Generator | None = None) -> None:
        from retarget.learn.columns import residual_columns
        from retarget.learn.expert_bc import ExpertBCLearner
        c = self.config
        residual = residual_columns(env, c.actor_group, c.residual, self.name)
        if self._windows is not None:
            self.learner = ExpertBCLearner(c.dagger(), env.obs_dims, env.action_dim,
                                           env.num_envs, self._windows(env.action_dim),
                                           c.demo_share, generator, residual)  # fmt: skip
            return
        try:
            self.learner = ExpertBCLearner(c.dagger(), env.obs_dims, env.action_dim,
                                           env.num_envs, None, c.demo_share, generator,
                                           residual)  # fmt: skip
        except ValueError as exc:
            raise PluginError(str(exc), plugin=self.name) from None

    def _load_windows(self, env: VecEnv) -> Any:
        """The expert's data for the env's clips, read when training starts (evaluating,
        playing and exporting a student need no expert directory)."""
        import numpy as np

        from retarget.expert.store import load_track
        from retarget.learn.expert_bc import ExpertWindows, tracked_part
        c = self.config
        env = tracking_env(env, self.name)
        root = Path(c.expert)
        sim = env.sim
        shapes = {k: tuple(sim.raw(k).shape[1:]) for k in sim.STATE_FIELDS}
        nq, nv = shapes["qpos"][0], shapes["qvel"][0]
        lib, ref = env.library, env.reference  # type: ignore[attr-defined]
        clips = []
        for i, name in enumerate(lib.names):
            file = root / "clips" / f"{name}.npz"
            if not file.exists():
                raise PluginError(f"the expert has not planned clip {name!r} ({file})",
                                  plugin=self.name, hint="run `retarget expert` on it first")
            data = load_track(file, nq=nq, nv=nv, nu=env.action_dim, state_shapes=shapes)
            start = int(lib.start[i])
            if len(data["qpos"]) > int(lib.length[i]) or not np.allclose(
                data["ref_qpos0"], ref.qpos64[start], atol=1e-4
            ):
                raise PluginError(f"clip {name!r} is not the clip the expert planned",
                                  plugin=self.name, hint=str(file))
            clips.append(tracked_part(data))
        return ExpertWindows(clips, sim.STATE_FIELDS)

    def train_iteration(self, env: VecEnv) -> IterationResult:
        learner = self._ready()
        if learner.windows is None:
            learner.windows = self._load_windows(env)
        return IterationResult(stats=learner.train_iteration(env))



@retarget.hookimpl
def register_algorithms(register) -> None:
    register(ExpertBC)
