"""DAgger distillation as an algorithm plugin: a student learns a trained teacher's actions.

``algorithm: {type: dagger, teacher: runs/human-teacher/latest}`` (or ``retarget train
--sensors three_point --teacher RUN``). Before the run starts, :meth:`Dagger.prepare_recipe`
reads the teacher's ``recipe.lock.yaml``: the teacher must be the same character with the
same physics (control rate, substeps, actuation and PD gains), else the run is refused naming
both; the teacher's sensors and observers are added to the student's recipe and its actor
inputs become the ``teacher`` observation group, while the student's ``actor`` group keeps
the student's own sensors. The locked recipe therefore says exactly what ran, and the
student evaluates, resumes and exports (ONNX) without the teacher.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import retarget
from retarget import IterationResult, PluginError, RecipeError, VecEnv
from retarget.kinds.capabilities import Exportable
from retarget.learn.config import DaggerConfig
from retarget.learn.delegating import LearnerAlgorithm
from retarget.settings.sim import ACTION_PHYSICS

if TYPE_CHECKING:
    import torch

    from retarget.learn.dagger import DaggerLearner

PHYSICS = ACTION_PHYSICS
"""Simulation settings a teacher's actions depend on: they must match the student's."""


def _names(components: list[Any]) -> list[str]:
    return [c["type"] if isinstance(c, dict) else str(c) for c in components]


def _changed_sensors(
    sensors: list[Any], actor: list[str], changes: Mapping[str, Mapping[str, Any]], lock: Path
) -> list[Any]:
    """The teacher's sensors with ``algorithm.teacher_sensors`` applied; a name that is not
    one of the teacher's sensors is refused naming the ones it has."""
    names = _names(sensors)
    unknown = [n for n in changes if n not in names or n not in actor]
    if unknown:
        raise RecipeError(
            f"the teacher has no sensor {', '.join(map(repr, unknown))} (its sensors: "
            f"{', '.join(n for n in names if n in actor) or 'none'})",
            file=str(lock), field="algorithm.teacher_sensors",
        )  # fmt: skip
    out = []
    for name, comp in zip(names, sensors, strict=True):
        if name in changes:
            comp = {**(comp if isinstance(comp, dict) else {"type": comp}), **changes[name]}
        out.append(comp)
    return out


def _actor_sources(recipe: Mapping[str, Any], group: str = "actor") -> list[str]:
    """The sources of a recipe's actor group (its explicit groups or the default one)."""
    groups = (recipe.get("env") or {}).get("groups")
    if groups:
        if group not in groups:
            raise RecipeError(f"the recipe has no observation group '{group}'",
                              field="env.groups")
        return list(groups[group])
    return [*_names(recipe.get("sensors", [])), "proprio", *_names(recipe.get("observers", []))]


class Dagger(LearnerAlgorithm[DaggerConfig]):
    """Online distillation (DAgger): the student acts, a frozen teacher run labels its states.

    The student reads the ``actor`` group (e.g. headset + controllers), the teacher its own
    ``teacher`` group (e.g. the full reference body) of the same environment. Loss: MSE on
    the action means (or the Gaussians' KL); ``beta`` lets the teacher act early on.
    """

    name = "dagger"
    learns_from_reward = False

    def __init__(
        self,
        config: DaggerConfig | None = None,
        teacher: Callable[[int, int], torch.nn.Module] | None = None,
    ) -> None:
        """``teacher``: builds the labelling policy from (teacher input width, action count)
        instead of loading the configured run (tests, teachers that are not runs)."""
        super().__init__(config)
        self.learner: DaggerLearner | None = None
        self.registry: Any = None
        self._teacher_factory = teacher

    @classmethod
    def example(cls) -> Dagger:
        """Distils a fixed linear teacher reading the ``critic`` group: no teacher run."""
        import torch

        def linear(width: int, actions: int) -> torch.nn.Module:
            layer = torch.nn.Linear(width, actions)
            g = torch.Generator().manual_seed(0)
            with torch.no_grad():
                layer.weight.copy_(torch.randn(actions, width, generator=g) * 0.3)
                layer.bias.zero_()
            return torch.nn.Sequential(layer, torch.nn.Tanh())

        return cls(DaggerConfig(teacher="example", teacher_group="critic"), teacher=linear)

    # ------------------------------------------------------------------ the recipe

    def prepare_recipe(self, recipe: dict[str, Any], registry: Any) -> dict[str, Any]:
        from retarget.recipe import parse_text
        from retarget.train.run_dir import LOCK, latest_checkpoint, resolve_run
        c = self.config
        run = resolve_run(c.teacher)
        lock_file = run / LOCK
        try:
            text = lock_file.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as exc:
            raise RecipeError(f"cannot read the teacher's recipe: {exc}",
                              file=str(lock_file)) from None
        teacher = parse_text(text, str(lock_file), ".yaml").data  # bounded, no duplicates
        if not isinstance(teacher, dict) or "character" not in teacher:
            raise RecipeError("not a run's recipe (no character)", file=str(lock_file))
        self._check_match(recipe, teacher, lock_file)
        recipe = dict(recipe)
        student_actor = _actor_sources(recipe, c.actor_group)
        teacher_actor = _actor_sources(teacher)
        own = list(teacher.get("sensors") or [])
        changed = _changed_sensors(own, teacher_actor, c.teacher_sensors, lock_file)
        trained = dict(zip(_names(own), own, strict=True))
        for slot in ("sensors", "observers"):
            mine = list(recipe.get(slot) or [])
            have = {n: comp for n, comp in zip(_names(mine), mine, strict=True)}
            for comp in (changed if slot == "sensors" else teacher.get(slot) or []):
                name = _names([comp])[0]
                if name not in teacher_actor:
                    continue
                as_trained = name in c.teacher_sensors and have.get(name) == trained.get(name)
                if slot == "sensors" and as_trained:
                    # a lock's copy of the teacher's sensor as it trained: changed with it
                    at = _names(mine).index(name)
                    mine[at] = have[name] = comp
                if name in have and have[name] != comp:
                    source = (f"{lock_file} with algorithm.teacher_sensors"
                              if slot == "sensors" and name in c.teacher_sensors else lock_file)
                    raise RecipeError(
                        f"{slot[:-1]} '{name}' is configured differently from the teacher's "
                        f"({comp} from {source}, {have[name]} here)",
                        field=slot,
                        hint="use the teacher's settings for a sensor both read (with "
                        "algorithm.teacher_sensors applied)",
                    )
                if name not in have:
                    mine.append(comp)
            recipe[slot] = mine
        # the teacher reads references: they must stand as the ones it learned on (a teacher
        # recorded before motions.level_feet learned on tilted feet, and falls on level ones)
        taught = teacher.get("motions")
        level = isinstance(taught, dict) and bool(taught.get("level_feet", False))
        recipe["motions"] = {**(recipe.get("motions") or {}), "level_feet": level}
        env = dict(recipe.get("env") or {})
        # and its elbows bend as they did (env.hinge_elbows; a lock without it: bend alone)
        taught_env = teacher.get("env")
        env["hinge_elbows"] = isinstance(taught_env, dict) and bool(
            taught_env.get("hinge_elbows", False)
        )
        groups = dict(env.get("groups") or {})
        groups[c.actor_group] = student_actor
        groups[c.teacher_group] = teacher_actor
        env["groups"] = groups
        recipe["env"] = env
        algorithm = dict(recipe["algorithm"])
        # the directory itself, not a moving 'latest' link (a shipped model keeps its name)
        shipped = str(c.teacher).startswith("pretrained:")
        algorithm["teacher"] = str(c.teacher) if shipped else str(run)
        if not algorithm.get("teacher_checkpoint"):  # the weights of now, if it trains on
            algorithm["teacher_checkpoint"] = str(latest_checkpoint(run).relative_to(run))
        recipe["algorithm"] = algorithm
        return recipe

    @staticmethod
    def _check_match(student: Mapping[str, Any], teacher: Mapping[str, Any], lock: Path) -> None:
        def character(r: Mapping[str, Any]) -> Any:
            ch = r["character"]
            return ch if isinstance(ch, dict) else {"type": ch}

        mine, theirs = character(student), character(teacher)
        if mine.get("type") != theirs.get("type") or {
            k: v for k, v in mine.items() if k in theirs
        } != {k: v for k, v in theirs.items() if k in mine}:
            raise RecipeError(
                f"the teacher drives character {theirs}, this recipe {mine}",
                file=str(lock),
                field="character",
                hint="distil from a teacher trained on the same character and settings",
            )
        sim_s, sim_t = student.get("sim") or {}, teacher.get("sim") or {}
        for key in PHYSICS:
            if key in sim_s and key in sim_t and sim_s[key] != sim_t[key]:
                raise RecipeError(
                    f"the teacher ran with sim.{key}={sim_t[key]}, this recipe with "
                    f"sim.{key}={sim_s[key]}: the teacher's actions mean something else here",
                    file=str(lock),
                    field=f"sim.{key}",
                    hint=f"--set sim.{key}={sim_t[key]}",
                )

    # ------------------------------------------------------------------ training

    def connect(self, registry: Any) -> None:
        self.registry = registry

    def setup(self, env: VecEnv, generator: torch.Generator | None = None) -> None:
        from retarget.learn.columns import image_inputs, residual_columns
        from retarget.learn.dagger import DaggerLearner
        c = self.config
        residual = residual_columns(env, c.actor_group, c.residual, self.name)
        try:
            images = image_inputs(env, c.actor_group)
            self.learner = DaggerLearner(
                c, env.obs_dims, env.action_dim, env.num_envs, generator, images,
                comm=self.comm, residual=residual,
            )
        except ValueError as exc:
            raise PluginError(str(exc), plugin=self.name) from None
        self._teacher_dim = int(env.obs_dims[self.config.teacher_group])
        if self._teacher_factory is not None:
            self.learner.set_teacher(self._teacher_factory(self._teacher_dim, env.action_dim))

    def _load_teacher(self) -> None:
        """The teacher run's deployable policy, loaded once, when training starts (acting,
        evaluating and exporting a student never need it)."""
        from retarget.motion.procedural import idle_clip
        from retarget.train.load import load_run
        from retarget.train.run_dir import resolve_run
        if self.registry is None:
            raise PluginError(
                "needs the plugin registry to load its teacher run", plugin=self.name,
                hint="the trainer calls connect(registry) before setup",
            )
        run = resolve_run(self.config.teacher)
        ckpt = self.config.teacher_checkpoint
        teacher = load_run(
            run, self.registry, num_envs=1, clips=[idle_clip(1.0)],
            checkpoint=run / ckpt if ckpt else None,
        )
        if not isinstance(teacher.algorithm, Exportable):
            raise PluginError(f"the teacher run {run} has no policy to distil", plugin=self.name)
        group, policy = teacher.algorithm.policy()
        width = int(teacher.env.obs_dims[group])
        if width != self._teacher_dim:
            raise PluginError(
                f"the teacher's '{group}' input has {width} columns, this environment's "
                f"'{self.config.teacher_group}' group {self._teacher_dim}",
                plugin=self.name,
                hint="the student's recipe must add the teacher's sensors unchanged",
            )
        self._ready().set_teacher(policy)

    def train_iteration(self, env: VecEnv) -> IterationResult:
        learner = self._ready()
        if learner.teacher is None:
            self._load_teacher()
        return IterationResult(stats=learner.train_iteration(env))

    def fresh_rank(self, generator: torch.Generator) -> None:
        self._ready().fresh_rank(generator)

    def warm_start(self, state: Mapping[str, Any], inputs: Mapping[str, torch.Tensor]) -> None:
        self._ready().warm_start(state, inputs)


@retarget.hookimpl
def register_algorithms(register) -> None:
    register(Dagger)
