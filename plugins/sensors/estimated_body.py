"""The pose estimator as a sensor: a two-stage tracker's first stage, composable in recipes.

``sensors: [three_point, {type: estimated_body, estimator: runs/EST/latest}]`` gives a policy
the output of a trained pose estimator run (:mod:`retarget.learn.estimator`) beside the raw
devices: the estimated body in the headset frame (root, 6D rotations), the foot-contact
probabilities and each joint's position uncertainty, computed every step from the same device
window a headset has. A physics policy trained (or distilled) with it follows the estimated
full body, as KinPoly-v does; the uncertainty is an input, so it can learn when to trust the
estimate. The estimator's own sensors are rebuilt from its run and read the headset frame
exactly as in its training (the character's root replaced by the headset's ground point).
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING, Any

from pydantic import Field

import retarget
from retarget import (
    Layout,
    ObsSpec,
    PluginConfig,
    PluginError,
    RecipeError,
    RetargetError,
    Sensor,
    StepContext,
)
from retarget.kinds.capabilities import Exportable, PoseEstimating

if TYPE_CHECKING:
    import torch

    from retarget.kinds.lookup import PluginLookup


class EstimatedBodyConfig(PluginConfig):
    estimator: str | None = Field(
        None, description="a pose estimator run (runs/NAME/latest); None: an untrained "
        "estimator over a 3-frame three-point window (tests and the contract suite)",
    )  # fmt: skip
    checkpoint: str | None = Field(
        None, description="the estimator run's checkpoint, relative to the run; a new run "
        "locks the newest one (None: the newest when the sensor is bound)",
        pattern=r"^checkpoints/ckpt-[0-9]+\.pt$",
    )  # fmt: skip


class EstimatedBody(Sensor[EstimatedBodyConfig]):
    """A trained pose estimator's body, contacts and uncertainty from the device window."""

    name = "estimated_body"
    requires = ("site:head", "site:left_hand", "site:right_hand")

    def __init__(self, config: PluginConfig | None = None) -> None:
        super().__init__(config)
        self._net: torch.nn.Module | None = None
        self._inner: list[Sensor[Any]] = []

    def bind(self, layout: Layout) -> None:
        super().bind(layout)
        self._layout = layout
        if self.config.estimator is None:
            self._bind_untrained(layout)
        else:
            self._bind_run(layout, self.config.estimator)

    def _bind_untrained(self, layout: Layout) -> None:
        """A fixed, untrained estimator over three-point devices (tests, the contract kit)."""
        import torch

        from retarget.learn.estimator import DeployedEstimator, PoseNet

        if self.registry is not None:  # the recipe's own three_point, when connected
            cls = self.registry.get("sensor", "three_point").cls
        else:
            from retarget.plugins.sensors.devices import ThreePoint as cls
        inner = cls(cls.Config.model_validate({"past": 2}))
        inner.bind(layout)
        self._inner = [inner]
        size = int(inner.spec(layout).size)
        with torch.random.fork_rng(devices=[]):  # a fixed net; the run's RNG untouched
            torch.manual_seed(0)
            self._net = DeployedEstimator(PoseNet(size, (64,))).eval()

    def pinned_config(self, registry: PluginLookup) -> EstimatedBodyConfig | None:
        """The estimator run's directory and newest checkpoint, fixed in the new run's lock
        (not a moving ``latest``); a run that is not a pose estimator is refused here."""
        from retarget.recipe import parse_text
        from retarget.train.run_dir import LOCK, latest_checkpoint, resolve_run

        name = self.config.estimator
        if name is None:
            return None
        try:
            run = resolve_run(name)
            lock = parse_text((run / LOCK).read_text(encoding="utf-8"), str(run / LOCK),
                              ".yaml").data  # fmt: skip
            algorithm = lock["algorithm"]
            kind = algorithm if isinstance(algorithm, str) else algorithm["type"]
            latest = latest_checkpoint(run)
        except (OSError, UnicodeDecodeError, KeyError, TypeError, RetargetError) as exc:
            raise RecipeError(f"cannot read the estimator run {name}: {exc}",
                              field="sensors", plugin=self.name) from None  # fmt: skip
        if not issubclass(registry.get("algorithm", kind).cls, PoseEstimating):
            raise RecipeError(f"{name} is a '{kind}' run, not a pose estimator",
                              field="sensors", plugin=self.name)  # fmt: skip
        checkpoint = self.config.checkpoint or str(latest.relative_to(run))
        shipped = name.startswith("pretrained:")  # a shipped model keeps its name
        return self.config.model_copy(
            update={"estimator": name if shipped else str(run), "checkpoint": checkpoint}
        )

    def _bind_run(self, layout: Layout, run: str) -> None:
        """The estimator run's own sensors and deployed network, resolved against the
        recipe's plugins (as a student resolves its teacher)."""
        from retarget.motion.procedural import idle_clip
        from retarget.train.load import load_run

        if self.registry is None:
            raise PluginError(
                "needs the plugin registry to load its estimator run", plugin=self.name,
                hint="environments built from a recipe connect(registry) before bind",
            )
        from retarget.train.run_dir import resolve_run

        ckpt = self.config.checkpoint
        where = resolve_run(run)
        loaded = load_run(where, self.registry, num_envs=1, clips=[idle_clip(2.0)],
                          checkpoint=where / ckpt if ckpt else None)  # fmt: skip
        algorithm = loaded.algorithm
        if not (isinstance(algorithm, PoseEstimating) and isinstance(algorithm, Exportable)):
            raise PluginError(f"{run} is not a pose estimator run", plugin=self.name)
        if loaded.env.observers:
            raise PluginError(f"{run} reads the scene (observers); as a sensor only "
                              "device-only estimators are supported", plugin=self.name)  # fmt: skip
        self._inner = list(loaded.env.sensors)
        for sensor in self._inner:
            sensor.bind(layout)
        self._net = algorithm.policy()[1].eval()

    def deployable(self) -> tuple[torch.nn.Module, int, dict[str, Any]]:
        if self._net is None:
            raise PluginError("deployable() before bind(layout)", plugin=self.name)
        width = sum(int(s.spec(self._layout).size) for s in self._inner)
        return self._net, width, {
            "frame": "headset (the current headset's ground point and heading)",
            "inputs": [{"name": s.name, "size": int(s.spec(self._layout).size)}
                       for s in self._inner],
            "estimator": self.config.estimator,
        }  # fmt: skip

    def frames_needed(self) -> tuple[int, int]:
        if not self._inner:
            raise PluginError("frames_needed() before bind(layout)", plugin=self.name)
        return (max(s.frames_needed()[0] for s in self._inner), 0)

    def spec(self, layout: Layout) -> ObsSpec:
        from retarget.learn.estimator import DEPLOYED_SIZE

        return ObsSpec((DEPLOYED_SIZE,))

    def observe(self, ctx: StepContext) -> torch.Tensor:
        import torch

        from retarget.learn.pose_samples import HeadsetFrame

        if self._net is None:
            raise PluginError("observe() before bind(layout)", plugin=self.name)
        now = ctx.ref.devices[:, list(ctx.ref.window_offsets).index(0), 0]
        frame = HeadsetFrame.of(now)
        qpos = ctx.sim.qpos.clone()
        qpos[:, :3], qpos[:, 3:7] = now[:, :3], frame.yaw
        headset_ctx = replace(ctx, sim=replace(ctx.sim, qpos=qpos))
        n = ctx.num_envs
        inputs = torch.cat([s.observe(headset_ctx).reshape(n, -1).float() for s in self._inner],
                           dim=-1)  # fmt: skip
        with torch.no_grad():
            return self._net(inputs)


@retarget.hookimpl
def register_sensors(register) -> None:
    register(EstimatedBody)
