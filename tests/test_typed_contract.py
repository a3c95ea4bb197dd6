"""The typed contract: a plugin names its config as its base's parameter, and an iteration
returns a typed result (statistics, samples learnt from, the progress bar's figures)."""

from __future__ import annotations

import pytest
import torch

import retarget
from retarget import IterationResult, PluginConfig
from retarget.kinds.iteration import as_result
from retarget.testing import checks


class HeightConfig(PluginConfig):
    limit: float = 0.5


class Low(retarget.Termination[HeightConfig]):
    """Ends an episode when the root is low."""

    name = "low"

    def check(self, ctx: retarget.StepContext) -> torch.Tensor:
        return ctx.sim.qpos[:, 2] < self.config.limit


def test_the_base_parameter_is_the_config() -> None:
    assert Low.Config is HeightConfig
    assert Low().config == HeightConfig() and Low({"limit": 0.2}).config.limit == 0.2
    with pytest.raises(Exception, match="limit"):
        Low({"limit": "high"})


def test_a_config_that_contradicts_the_parameter_is_refused_at_class_definition() -> None:
    class Other(PluginConfig):
        pass

    with pytest.raises(TypeError, match="HeightConfig named in its base"):
        class Clash(retarget.Termination[HeightConfig]):
            """Clashes."""

            name = "clash"
            Config = Other

            def check(self, ctx):
                return ctx.sim.qpos[:, 2] < 0


def test_setting_config_in_the_body_still_works() -> None:
    class Plain(retarget.Termination):
        """Old style."""

        name = "plain"
        Config = HeightConfig

        def check(self, ctx):
            return ctx.sim.qpos[:, 2] < self.config.limit

    assert Plain().config.limit == 0.5


def test_built_in_plugins_name_their_config() -> None:
    from retarget.plugins.rewards.link import LinkPos, LinkPosConfig
    from retarget.plugins.scenes.boxes import Boxes, BoxesConfig

    assert LinkPos.Config is LinkPosConfig and Boxes.Config is BoxesConfig


def test_iteration_results_hold_numbers() -> None:
    result = IterationResult(stats={"loss": torch.tensor(0.5).item(), "n": 3})
    assert result.stats == {"loss": 0.5, "n": 3.0} and result.samples is None
    with pytest.raises(TypeError, match="'what'"):
        IterationResult(stats={"what": "text"})
    with pytest.raises(ValueError, match="samples"):
        IterationResult(stats={}, samples=-1)
    assert IterationResult(stats={"x": float("nan")}).non_finite().keys() == {"x"}
    assert as_result({"loss": 1.0}).stats == {"loss": 1.0}
    with pytest.raises(TypeError, match="IterationResult"):
        as_result([1.0])  # type: ignore[arg-type]


def test_a_kinematic_algorithm_must_count_its_samples() -> None:
    """Without stepping the environment, an uncounted iteration never spends the budget."""
    from retarget.plugins.algorithms.estimator import Estimator

    class Uncounted(Estimator):
        """Forgets to say how many samples it learnt from."""

        name = "uncounted"

        def train_iteration(self, env):
            return dict(super().train_iteration(env).stats)

    checks.check_algorithm_update(Estimator)
    with pytest.raises(AssertionError, match="samples"):
        checks.check_algorithm_update(Uncounted)


def test_the_progress_bar_shows_the_iteration_headline() -> None:
    from retarget.cli.train_cmd import _figures

    last = {"loss": 0.25, "mpjpe_mm": 41.0, "episode_return": 3.0, "episode_length": 20.0}
    assert _figures(last, ("loss", "mpjpe_mm")) == "loss   0.250  mpjpe  41.0 mm"
    assert _figures(last, ("episode_return", "episode_length")).startswith("return    3.00")
    assert _figures({"custom": 1.5}, ("custom", "absent")) == "custom 1.5"


def test_tracking_env_names_what_an_environment_lacks() -> None:
    from retarget.kinds.tracking_env import tracking_env
    from retarget.testing.fakes import FakeVecEnv

    with pytest.raises(retarget.PluginError, match="has no last_context, layout, library"):
        tracking_env(FakeVecEnv(num_envs=2), "estimator")


def test_the_retarget_env_is_a_tracking_env() -> None:
    from retarget.env.build import env_from_recipe
    from retarget.kinds.tracking_env import tracking_env
    from retarget.recipe import load

    registry = retarget.load_plugins()
    env = env_from_recipe(load(None, registry, shorthands={"sensors": "three_point"}),
                          num_envs=2, registry=registry)  # fmt: skip
    assert tracking_env(env, "test") is env and env.last_context is None
    env.reset()
    env.step(torch.zeros(2, env.action_dim))
    assert env.last_context is not None and env.last_context.num_envs == 2


def test_built_in_algorithms_have_the_capabilities_they_define() -> None:
    from retarget.kinds.capabilities import capabilities

    registry = retarget.load_plugins()
    got = {n: capabilities(registry.get("algorithm", n).cls)
           for n in ("ppo", "dagger", "estimator", "expert_bc")}  # fmt: skip
    assert got == {
        "ppo": ["acting", "exportable", "warm_startable", "data_parallel"],
        "dagger": ["acting", "exportable", "warm_startable", "data_parallel"],
        "estimator": ["exportable", "post_staged", "pose_estimating", "warm_startable"],
        "expert_bc": ["acting", "exportable"],
    }


def test_require_names_the_algorithm_and_what_it_lacks() -> None:
    from retarget.kinds.capabilities import Acting, WarmStartable, require
    from retarget.plugins.algorithms.estimator import Estimator
    from retarget.plugins.algorithms.ppo import PPO

    ppo = PPO()
    assert require(ppo, WarmStartable) is ppo
    with pytest.raises(retarget.PluginError, match=r"algorithm estimator.*drives no character"):
        require(Estimator(), Acting, hint="eval it instead")


def test_an_algorithm_that_neither_acts_nor_estimates_fails_the_kit() -> None:
    import contract_doubles as d

    class Mute(d.GoodAlgorithm):
        """Trains, but there is nothing to evaluate or deploy."""

        name = "mute"
        act = None  # type: ignore[assignment]

    checks.check_algorithm_update(d.GoodAlgorithm)
    with pytest.raises(AssertionError, match=r"acts .* or estimates poses"):
        checks.check_algorithm_update(Mute)
