"""A kinematic pose estimator as an algorithm plugin (EnvPoser stage I): no physics, no actions.

``retarget train --algorithm estimator --sensors three_point`` (or ``hmd``; with ``observers``
such as ``height_map`` it also reads the scene around the user) trains, on the run's
motion library with synthesised devices, a network from a window of device features to the
whole canonical body with per-joint uncertainty and foot contacts
(:mod:`retarget.learn.estimator`). Before the run starts, :meth:`Estimator.prepare_recipe`
widens the device sensors' ``past`` to the estimator's ``window`` and sets one environment
(nothing is simulated while training). ``retarget eval`` measures it with the same metrics as
policies (:mod:`retarget.eval.kinematic`), and ``retarget export --onnx`` writes it with a
sidecar describing inputs (headset frame) and outputs.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from pydantic import Field

import retarget
from retarget import Algorithm, IterationResult, PluginConfig, PluginError, VecEnv
from retarget.kinds.tracking_env import tracking_env

if TYPE_CHECKING:
    import torch

    from retarget.kinds.deploy_stage import DeployStage
    from retarget.learn.estimator import EstimatorLearner


class EstimatorConfig(PluginConfig):
    window: int = Field(
        16, ge=1, le=256,
        description="device frames the estimator reads (now and window-1 past); the device "
        "sensors' past is widened to window-1",
    )  # fmt: skip
    hidden: list[int] = Field([512, 512], min_length=1, max_length=8)
    learning_rate: float = Field(1e-3, gt=0, le=1)
    batch_size: int = Field(2048, gt=0, le=1_000_000, description="frames per gradient step")
    updates_per_iteration: int = Field(4, gt=0, le=10_000)
    mirror: bool = Field(True, description="mirror half of each batch (left/right swapped)")
    rot_weight: float = Field(0.1, ge=0, description="weight of the rotations' NLL")
    contact_weight: float = Field(0.1, ge=0, description="weight of the contacts' BCE")
    scale_range: float = Field(
        0.1, ge=0, le=0.5, description="each sample's person scaled by 1 +- this (body sizes)"
    )
    input_noise: float = Field(
        0.1, ge=0, le=2, description="std of noise on the normalised inputs while training"
    )
    weight_decay: float = Field(1e-4, ge=0, le=1, description="AdamW weight decay")
    lost_controllers: float = Field(
        0.1, ge=0, le=1, description="chance per controller and sample that it is held still "
        "over the window (tracking lost), so the hands' uncertainty learns to rise then",
    )  # fmt: skip
    reach_controllers: bool | None = Field(
        True, description="put the estimate's wrists on the controllers by two-bone IK along "
        "the person's own arm (retarget.learn.reach: the skeleton the motions give), where "
        "the sensors read the controllers; held-out hands 5.3 -> 2.1 cm on gestures, "
        "3.3 -> 1.6 on runs; null (older runs) is off",
    )  # fmt: skip


class Estimator(Algorithm[EstimatorConfig]):
    """Supervised pose estimation from device windows, Gaussian NLL with per-joint variance.

    A kinematic method: it outputs the human body, not actions, so ``act`` refuses and
    ``retarget eval`` evaluates it by placing the character in the estimated pose each frame.
    """

    name = "estimator"
    learns_from_reward = False

    @classmethod
    def example(cls) -> Estimator:
        """Small enough for the contract suite's few updates."""
        return cls(EstimatorConfig(window=4, hidden=[32], batch_size=64,
                                   updates_per_iteration=1))  # fmt: skip

    def __init__(self, config: PluginConfig | None = None) -> None:
        super().__init__(config)
        self.learner: EstimatorLearner | None = None

    def prepare_recipe(self, recipe: dict[str, Any], registry: Any) -> dict[str, Any]:
        cfg = self.config
        recipe = dict(recipe)
        sensors = []
        for comp in recipe.get("sensors") or []:
            if isinstance(comp, dict) and "past" in comp:
                comp = {**comp, "past": max(int(comp["past"]), cfg.window - 1)}
            sensors.append(comp)
        recipe["sensors"] = sensors
        recipe["env"] = {**(recipe.get("env") or {}), "num_envs": 1}
        return recipe

    def _ready(self) -> EstimatorLearner:
        if self.learner is None:
            raise PluginError("setup(env) must be called first", plugin=self.name)
        return self.learner

    def setup(self, env: VecEnv, generator: torch.Generator | None = None) -> None:
        import torch

        from retarget.learn.estimator import EstimatorLearner, EstimatorSettings

        env = tracking_env(env, self.name)
        sensors = list(env.sensors)
        if not sensors:
            raise PluginError("needs at least one sensor (hmd or three_point)", plugin=self.name)
        for s in sensors:
            if s.recorded is not None:
                raise PluginError(
                    f"reads device poses; sensor '{s.name}' gives recorded images",
                    plugin=self.name, hint="use --sensors hmd or three_point",
                )  # fmt: skip
        cfg = self.config
        # with observers the scene is read as it is: a mirrored or resized person would no
        # longer match it, so those augmentations are off
        scene_aware = bool(list(getattr(env, "observers", ())))
        settings = EstimatorSettings(
            hidden=tuple(cfg.hidden), lr=cfg.learning_rate, batch_size=cfg.batch_size,
            updates_per_iteration=cfg.updates_per_iteration,
            mirror=cfg.mirror and not scene_aware,
            rot_weight=cfg.rot_weight, contact_weight=cfg.contact_weight,
            scale_range=0.0 if scene_aware else cfg.scale_range, input_noise=cfg.input_noise,
            weight_decay=cfg.weight_decay, lost_controllers=cfg.lost_controllers,
            reach=bool(cfg.reach_controllers),
        )  # fmt: skip
        self.learner = EstimatorLearner(env, settings, generator or torch.Generator())

    def train_iteration(self, env: VecEnv) -> IterationResult:
        stats = dict(self._ready().train_iteration())
        samples = int(stats.pop("samples"))  # rows of the library, no environment steps
        return IterationResult(stats=stats, samples=samples, headline=("loss", "mpjpe_mm"))

    def pose_estimator(self) -> EstimatorLearner:
        return self._ready()

    def policy(self) -> tuple[str, torch.nn.Module]:
        from retarget.learn.estimator import DeployedEstimator

        return "estimator", DeployedEstimator(self._ready().net).eval()

    def export_metadata(self, env: Any) -> dict[str, Any]:
        from retarget.motion import skeleton as sk

        learner = self._ready()
        layout = env.layout
        return {
            "kind": "pose_estimator",
            "obs_dim": learner.obs_dim,
            "frame": "headset: the current headset's ground point and heading (x ahead, "
            "y left, z up; heights are world heights); device features as the sensors "
            "compute them with the character root replaced by that frame",
            "observation_sources": [
                {"name": s.name, "size": int(s.spec(layout).size)}
                for s in (*env.sensors, *env.observers)
            ],
            "control_hz": env.sim.settings.control_hz,
            "reach_controllers": bool(learner.reach),
            "joints": list(sk.JOINT_NAMES),
            "outputs": [
                {"name": "root_pos", "size": 3},
                {"name": "rot6d", "size": 6 * sk.NUM_JOINTS,
                 "note": "root relative to the heading, then each joint's local rotation"},
                {"name": "contact_prob", "size": 2, "note": "left, right foot"},
                {"name": "position_std", "size": sk.NUM_JOINTS, "note": "metres, per joint"},
            ],
        }  # fmt: skip

    def post_stages(self) -> list[DeployStage]:
        """With ``reach_controllers``, the reach after the network (``reach.onnx``): what
        ``retarget eval`` measures is the reached estimate, so an application runs it too,
        with its user's bone offsets (the canonical skeleton's joints) and height."""
        import torch

        from retarget.kinds.deploy_stage import DeployStage
        from retarget.learn.estimator import DeployedEstimator
        from retarget.learn.pose_samples import sensor_inputs
        from retarget.learn.reach import ReachStage

        learner = self._ready()
        if not learner.reach:
            return []
        lib = learner.env.library
        rows = lib.start[:1].clone()
        inputs, frame = sensor_inputs(learner.env, rows)
        with torch.no_grad():
            estimate = DeployedEstimator(learner.net).eval()(inputs)
        ctrl = frame.poses_in(lib.devices[rows][:, 1:3])
        examples = {"estimate": estimate, "controllers": ctrl.float(),
                    "bones": lib.bones[:1].float(), "height": lib.heights[:1].float()}  # fmt: skip
        return [DeployStage("reach", ReachStage(), examples, ("reached",), {
            "note": "run on the estimator's output: its wrists reach the controllers along "
            "the user's own arm (what retarget eval measured); the output has the estimator's "
            "layout. While the runtime reports a controller untracked, keep the network's "
            "estimate instead (the reach would pin that hand to its last reported pose)",
            "controllers": "left, right: position and wxyz in the estimator's headset frame",
            "bones": "the user's bone offsets in the T-pose, one row per joint (the "
            "estimator's 'joints' order), metres",
            "height": "the user's standing height, metres (scales the controllers' mounts)",
        })]  # fmt: skip

    def warm_start(self, state: Mapping[str, Any], inputs: Mapping[str, torch.Tensor]) -> None:
        """``--init-from`` another estimator run: its network, retrained on this run's motions
        and devices (e.g. devices at the character's size, or another corpus)."""
        learner = self._ready()
        env = learner.env
        names = {src.name for src in (*env.sensors, *env.observers)}
        kept, at = True, 0
        for name, size in env.obs_layout["actor"]:  # the estimator reads these sources only
            if name in names:
                if "actor" not in inputs:
                    kept = False
                    break
                index = inputs["actor"][at : at + size]
                kept = kept and bool((index >= 0).all()) and bool((index.diff() == 1).all())
            at += size
        if not kept:
            raise ValueError("a pose estimator starts only from one that read the same "
                             "sensors with the same window (its device features)")
        learner.warm_start(state)

    def state_dict(self) -> dict[str, Any]:
        return self._ready().state_dict()

    def load_state_dict(self, state: Mapping[str, Any]) -> None:
        self._ready().load_state_dict(state)


@retarget.hookimpl
def register_algorithms(register) -> None:
    register(Estimator)
