"""The contract suite itself: well-behaved doubles pass, and each check catches its violation."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import contract_doubles as d
import mujoco
import numpy as np
import pytest
import torch
from doubles_outside_toolkit import Internal
from pydantic import ConfigDict

import retarget
from retarget.testing import check_plugin, checks, parametrize_with_checks


@parametrize_with_checks(d.GOOD, installed=False)
def test_good_doubles_pass(plugin, check) -> None:
    check(plugin)


def test_check_plugin_runs_everything_for_a_kind() -> None:
    names = [c.__name__ for c in checks.checks_for(d.GoodReward)]
    assert "check_vectorised" in names and "check_entry_point" in names
    check_plugin(d.GoodReward, installed=False)
    with pytest.raises(AssertionError, match="check_entry_point"):
        check_plugin(d.GoodReward)  # defined in a test module: not installed


# ---------------------------------------------------------------- broken variants


class BadName(d.GoodReward):
    """Bad name."""

    name = "Bad-Name"


class NoDoc(d.GoodReward):
    name = "no_doc"


class LooseConfig(d.GoodReward):
    """Accepts unknown config fields."""

    name = "loose_config"

    class Config(retarget.RewardConfig):
        model_config = ConfigDict(extra="allow", frozen=True)


class RequiredConfig(d.GoodReward):
    """Cannot be built with defaults."""

    name = "required_config"

    class Config(retarget.RewardConfig):
        gain: float


class NoSchema(d.GoodReward):
    """Config that cannot be described as JSON Schema."""

    name = "no_schema"

    class Config(retarget.RewardConfig):
        callback: Callable[[int], int] = abs


class Unregistered(d.GoodReward):
    """No hook registers this."""

    name = "unregistered"


class WrongShape(d.GoodReward):
    """Returns (N, 1)."""

    name = "wrong_shape"

    def compute(self, ctx):
        return super().compute(ctx)[:, None]


class NotFinite(d.GoodReward):
    """Returns -inf."""

    name = "not_finite"

    def compute(self, ctx):
        return torch.log(torch.zeros(ctx.num_envs))


class Coupled(d.GoodReward):
    """Normalises by the batch mean: environments influence each other."""

    name = "coupled"

    def compute(self, ctx):
        r = super().compute(ctx)
        return r - r.mean()


class Random(d.GoodReward):
    """Draws unseeded noise."""

    name = "random"

    def compute(self, ctx):
        return torch.rand(ctx.num_envs)


class FussyReset(d.GoodReward):
    """Only accepts resetting every environment."""

    name = "fussy_reset"

    def compute(self, ctx):
        self.n = ctx.num_envs
        return super().compute(ctx)

    def reset(self, env_ids):
        if len(env_ids) != self.n:
            raise RuntimeError("can only reset all environments")


class StickyReset(d.GoodReward):
    """Counts steps per environment but ``reset`` forgets to clear the rows it is given."""

    name = "sticky_reset"

    def compute(self, ctx):
        steps = getattr(self, "steps", torch.zeros(ctx.num_envs))
        self.steps = steps + 1
        return super().compute(ctx) + self.steps

    def reset(self, env_ids):
        pass


class NoJointMap(d.GoodCharacter):
    """Compiles and steps, but has no joint map: nothing can be retargeted onto it."""

    name = "no_joint_map"

    def joint_map(self):
        return None


class UndeclaredWindow(d.GoodSensor):
    """Reads five frames of the device window but declares it needs none."""

    name = "undeclared_window"

    def frames_needed(self):
        return (0, 0)


class Looping(d.GoodReward):
    """Loops over environments in Python."""

    name = "looping"

    def compute(self, ctx):
        out = torch.zeros(ctx.num_envs)
        for i in range(ctx.num_envs):
            out[i] = ctx.sim.site_pos[i, self.head, 2]
        return out


class EmptySpec(d.GoodSensor):
    """Declares a zero-sized observation."""

    name = "empty_spec"

    def spec(self, layout):
        return retarget.ObsSpec((0,))


class NoCompile(d.GoodCharacter):
    """An actuator targets a joint that does not exist."""

    name = "no_compile"

    def build_spec(self) -> mujoco.MjSpec:
        spec = super().build_spec()
        spec.add_actuator(name="ghost", target="ghost", trntype=mujoco.mjtTrn.mjTRN_JOINT)
        return spec


class ActuatedPassive(d.GoodCharacter):
    """Declares an actuated joint as passive."""

    name = "actuated_passive"

    def passive_joints(self):
        return ("spine",)


class Unlimited(d.GoodCharacter):
    """An actuator without a control range."""

    name = "unlimited"

    def build_spec(self) -> mujoco.MjSpec:
        spec = super().build_spec()
        spec.actuators[0].ctrllimited = False
        return spec


class Unstable(d.GoodCharacter):
    """Absurd gravity: accelerations blow up at the first step."""

    name = "unstable"

    def build_spec(self) -> mujoco.MjSpec:
        spec = super().build_spec()
        spec.option.gravity = [0, 0, -1e14]
        return spec


class BrokenBuild(d.GoodScene):
    """Raises while adding its geometry."""

    name = "broken_build"

    def build(self, spec):
        raise ValueError("no floor for you")


class Backwards(d.GoodReward):
    """Asks for the reference 0 frames ahead (offsets are frames >= 1)."""

    name = "backwards"

    def needs(self):
        return retarget.StepNeeds(reference_offsets=(0,))


class Unreplayable(d.GoodSensor):
    """Declares a recorded stream but cannot replay it."""

    name = "unreplayable"
    recorded = "images"


class FlatHeights(d.GoodScene):
    """Returns one height per environment instead of per point."""

    name = "flat_heights"

    def height_at(self, xy):
        return torch.zeros(xy.shape[0])


class GhostMocap(d.GoodScene):
    """Names a mocap body its build never adds."""

    name = "ghost_mocap"

    def mocap_bodies(self):
        return ("no_such_prop",)


class OnePlacement(d.GoodScene):
    """Ignores allocate(): every query answers for one environment only."""

    name = "one_placement"

    def height_at(self, xy):
        return torch.zeros(1, xy.shape[1])


class NanUpdate(d.GoodAlgorithm):
    """Reports a NaN loss."""

    name = "nan_update"

    def train_iteration(self, env):
        super().train_iteration(env)
        return {"loss": float("nan")}


class ForgetfulCheckpoint(d.GoodAlgorithm):
    """Saves nothing."""

    name = "forgetful_checkpoint"

    def state_dict(self) -> dict:
        return {}

    def load_state_dict(self, state) -> None:
        pass


class NotAClip(d.GoodFormat):
    """Returns a dict."""

    name = "not_a_clip"

    def read(self, path: Path):
        return {"fps": 30}


class LeakyErrors(d.GoodFormat):
    """Lets a ValueError escape on bad input."""

    name = "leaky_errors"

    def read(self, path: Path):
        lines = path.read_text(errors="replace").splitlines()
        return super().read(path) if lines else float("x")


class TwoArgRun(d.GoodCommand):
    """run takes an extra argument."""

    name = "two_arg_run"

    def run(self, args, extra):
        return 0


class Meddler(d.GoodCallback):
    """Writes into the statistics it is given (they are the trainer's, read-only)."""

    name = "meddler"

    def on_iteration(self, iteration, env_steps, stats) -> None:
        stats["loss"] = 0.0


class Misreported(d.GoodPlanner):
    """Reports actions other than the ones it stepped."""

    name = "misreported"

    def report(self, stepped):
        return np.clip(stepped + 0.2, -1, 1)


class Restless(d.GoodPlanner):
    """Plans each call with fresh randomness."""

    name = "restless"

    def perturb(self, targets):
        return targets + np.random.default_rng().normal(0.0, 0.01, targets.shape)


BROKEN = [
    (checks.check_name, BadName),
    (checks.check_docstring, NoDoc),
    (checks.check_config_strict, LooseConfig),
    (checks.check_config_strict, RequiredConfig),
    (checks.check_config_schema, NoSchema),
    (checks.check_registers_cleanly, Unregistered),
    (checks.check_uses_toolkit, Internal),
    (checks.check_entry_point, d.GoodReward),
    (checks.check_needs, Backwards),
    (checks.check_batched_shapes, WrongShape),
    (checks.check_finite, NotFinite),
    (checks.check_batch_invariance, Coupled),
    (checks.check_deterministic, Random),
    (checks.check_subset_reset, FussyReset),
    (checks.check_subset_reset, StickyReset),
    (checks.check_batched_shapes, UndeclaredWindow),
    (checks.check_vectorised, Looping),
    (checks.check_spec, EmptySpec),
    (checks.check_recorded, Unreplayable),
    (checks.check_character_compiles, NoCompile),
    (checks.check_character_retargets, NoJointMap),
    (checks.check_character_passive_unactuated, ActuatedPassive),
    (checks.check_character_torque_limits, Unlimited),
    (checks.check_character_zero_torque_steps, Unstable),
    (checks.check_scene_composes, BrokenBuild),
    (checks.check_scene_queries, FlatHeights),
    (checks.check_scene_placement, GhostMocap),
    (checks.check_scene_placement, OnePlacement),
    (checks.check_algorithm_update, NanUpdate),
    (checks.check_algorithm_checkpoint, ForgetfulCheckpoint),
    (checks.check_motion_format_reads_sample, NotAClip),
    (checks.check_motion_format_rejects_garbage, LeakyErrors),
    (checks.check_command_arguments, TwoArgRun),
    (checks.check_callback_events, Meddler),
    (checks.check_planner_tracks, Misreported),
    (checks.check_planner_deterministic, Restless),
]


def test_every_check_has_a_breaking_double() -> None:
    every = {c for kind in checks.BY_KIND.values() for c in kind} | set(checks.COMMON)
    every.add(checks.check_entry_point)
    covered = {check for check, _ in BROKEN}
    assert every <= covered, f"checks without a double: {[c.__name__ for c in every - covered]}"


@pytest.mark.parametrize(
    ("check", "broken"), BROKEN, ids=[f"{c.__name__}-{b.__name__}" for c, b in BROKEN]
)
def test_each_check_fails_on_its_violation(check, broken) -> None:
    good = next(g for g in d.GOOD if issubclass(broken, g))  # the double it derives from
    if check is not checks.check_entry_point and check is not checks.check_registers_cleanly:
        check(good)  # the unbroken parent passes the same check
    with pytest.raises(Exception):  # noqa: B017 - any failure counts, as in pytest
        check(broken)
