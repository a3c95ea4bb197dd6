"""PPO settings: the paper's Table 3 values, plus what this project had to decide itself.

Decisions (figures from ``benchmarks/bench_ppo_update.py`` on a 2-core machine):

* **Exploration noise 0.02 is read as the variance** of the fixed Gaussian, i.e. a standard
  deviation of sqrt(0.02) = 0.141 on actions in [-1, 1]. Read as a standard deviation it would
  be 1 % of the torque range, which with the paper's 4096 environments may still give a usable
  gradient but with this machine's few hundred gives almost none. ``noise_parameter: std``
  switches to the other reading; ``learn_std: true`` lets the optimiser adapt it.
* **Batch size 8192 is the minibatch size.** The paper collects 4096 envs x 16 steps = 65,536
  samples per iteration, i.e. 8 minibatches of 8192 per epoch. Here the default rollout is
  ``num_envs x rollout_steps`` = 8192 samples: one minibatch per epoch, which keeps the
  paper's minibatch size *and* its ratio of gradient steps to samples (5 per 8192).
* **Value normalisation** (on by default): the critic predicts returns scaled by running
  statistics. Per-step rewards here reach ~14 and gamma 0.97 makes returns of several hundred,
  so a value clip of 0.2 in raw units would let the critic move 0.2 per iteration; in
  normalised units the clip means 0.2 standard deviations, as intended.
* **Threads**: collection on 1 torch thread (torch's intra-op threads spin between the
  environment's small tensor ops and slow MuJoCo's 2-thread pool by ~40 %), the update on 2
  (1.8x faster than 1 for these network sizes; measured in perf_baseline.md and again here).
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from pydantic import Field

from retarget.kinds import PluginConfig

Hidden = Annotated[
    tuple[Annotated[int, Field(ge=1, le=8192)], ...],
    Field(min_length=1, max_length=16, description="hidden layer widths"),
]
"""Layer widths of an MLP: bounded, so a typo cannot ask for gigabytes of weights."""


RESIDUAL = Field(
    None,
    description="an actor observation source (e.g. reference_action) whose raw values are "
    "added to the network's output: the policy learns a residual around it (a policy cloned "
    "or distilled with one fine-tunes with PPO under the same one)",
)


class PPOConfig(PluginConfig):
    """PPO hyper-parameters (defaults: paper Table 3; the environment count is the recipe's
    ``env.num_envs``, one source of truth for every algorithm)."""

    rollout_steps: int = Field(
        32, gt=0, le=10_000, description="steps per env per iteration (measured)"
    )
    learning_rate: float = Field(1.2e-4, gt=0, le=1)
    gamma: float = Field(0.97, ge=0, lt=1)
    lam: float = Field(0.95, ge=0, le=1, description="GAE lambda")
    epochs: int = Field(5, gt=0, le=1000)
    minibatch_size: int = Field(
        8192, gt=0, le=10_000_000, description="samples per gradient step"
    )
    clip: float = Field(0.2, gt=0, description="policy ratio clip")
    value_clip: float | None = Field(0.2, gt=0, description="value change clip; null: none")
    value_loss_coef: float = Field(0.2, ge=0)
    entropy_coef: float = Field(0.0, ge=0)
    max_grad_norm: float = Field(1.0, gt=0)
    exploration_noise: float = Field(0.02, gt=0)
    noise_parameter: Literal["variance", "std"] = "variance"
    learn_std: bool = False
    activation: Literal["tanh", "elu", "relu"] = "tanh"
    actor_hidden: Hidden = (300, 200, 100)
    critic_hidden: Hidden = (400, 400, 300, 200)
    normalize_obs: bool = True
    obs_clip: float = Field(10.0, gt=0)
    normalize_values: bool = True
    normalize_advantages: bool = True
    actor_group: str = "actor"
    critic_group: str = "critic"
    collect_threads: int = Field(1, ge=0, description="torch threads while acting; 0: leave")
    update_threads: int = Field(2, ge=0, description="torch threads while updating; 0: leave")
    overlap: bool = Field(
        False,
        description="update on each rollout in a thread while the next is collected: more "
        "steps/s, one update of policy lag under a decoupled objective (retarget.learn.overlap)",
    )
    episode_window: int = Field(100, gt=0, description="finished episodes averaged in stats")
    critic_warmup: int = Field(
        0,
        ge=0,
        description="first iterations of a run in which only the critic learns: fine-tuning "
        "a distilled student (--init-from), whose critic starts untrained",
    )
    residual: str | None = RESIDUAL

    @property
    def init_std(self) -> float:
        """The Gaussian's standard deviation implied by ``exploration_noise``."""
        if self.noise_parameter == "variance":
            return math.sqrt(self.exploration_noise)
        return self.exploration_noise


class DaggerConfig(PluginConfig):
    """DAgger settings; the student's network matches PPO's actor so that PPO can fine-tune a
    distilled student with ``--init-from``."""

    teacher: str = Field(
        description="the teacher's run directory (runs/NAME/latest); its latest checkpoint "
        "labels the student's states"
    )
    teacher_checkpoint: str | None = Field(
        None,
        description="checkpoint inside the teacher's run (set when the run starts: its "
        "latest), so a resumed student keeps the same teacher",
        pattern=r"^checkpoints/ckpt-[0-9]+\.pt$",
    )
    teacher_group: str = Field("teacher", description="observation group the teacher reads")
    teacher_sensors: dict[str, dict[str, Any]] = Field(
        default_factory=dict,
        description="settings changed in the teacher's own sensors while it labels, by sensor "
        "name, e.g. {reference_action: {offset: 3}}: its residual's base a frame further "
        "ahead, so labels lead a teacher that lags its reference; the network is unchanged",
    )
    actor_group: str = Field("actor", description="observation group the student reads")
    rollout_steps: int = Field(32, gt=0, le=10_000, description="steps per env per iteration")
    learning_rate: float = Field(5e-4, gt=0, le=1)
    epochs: int = Field(4, gt=0, le=1000, description="passes over the buffer per iteration")
    minibatch_size: int = Field(
        2048, gt=0, le=10_000_000, description="samples per gradient step"
    )
    buffer_rollouts: int = Field(
        1, ge=1, le=64, description="recent rollouts trained on (1: only the newest)"
    )
    loss: Literal["mse", "kl"] = Field(
        "mse", description="mse on action means, or KL(teacher || student) of the Gaussians"
    )
    teacher_std: float = Field(0.141, gt=0, description="kl: the teacher's action std")
    action_noise: float = Field(
        0.05, ge=0, description="std of the noise added to the student's actions while "
        "collecting (visits states around its own trajectory)"
    )
    beta: float = Field(0.0, ge=0, le=1, description="start probability the teacher acts")
    beta_iterations: int = Field(
        0, ge=0, description="iterations over which beta falls linearly to 0"
    )
    max_grad_norm: float = Field(1.0, gt=0)
    activation: Literal["tanh", "elu", "relu"] = "tanh"
    actor_hidden: Hidden = (300, 200, 100)
    residual: str | None = RESIDUAL
    obs_clip: float = Field(10.0, gt=0)
    collect_threads: int = Field(1, ge=0, description="torch threads while acting; 0: leave")
    update_threads: int = Field(2, ge=0, description="torch threads while updating; 0: leave")
    overlap: bool = Field(
        False,
        description="update on each rollout in a thread while the next is collected: more "
        "steps/s, one update of policy lag under a decoupled objective (retarget.learn.overlap)",
    )
    episode_window: int = Field(100, gt=0, description="finished episodes averaged in stats")


class ExpertBCConfig(PluginConfig):
    """Behaviour cloning from a tracking expert; the student network matches PPO's actor so
    that PPO can fine-tune it with ``--init-from``."""

    expert: str = Field(description="the expert directory `retarget expert --out` wrote")
    actor_group: str = Field("actor", description="observation group the student reads")
    rollout_steps: int = Field(32, gt=0, le=10_000, description="steps per env per iteration")
    learning_rate: float = Field(5e-4, gt=0, le=1)
    epochs: int = Field(4, gt=0, le=1000, description="passes over the buffer per iteration")
    minibatch_size: int = Field(2048, gt=0, le=10_000_000, description="samples per step")
    buffer_rollouts: int = Field(8, ge=1, le=64, description="recent rollouts trained on")
    demo_share: float = Field(
        0.5, ge=0, le=1, description="share of replayed windows that are the beam's other "
        "members (states around the best path) rather than the best path"
    )
    max_grad_norm: float = Field(1.0, gt=0)
    activation: Literal["tanh", "elu", "relu"] = "tanh"
    actor_hidden: Hidden = (300, 200, 100)
    residual: str | None = RESIDUAL
    obs_clip: float = Field(10.0, gt=0)

    def dagger(self) -> DaggerConfig:
        """The same settings as the DAgger learner reads them (it is reused for the update)."""
        return DaggerConfig(
            teacher="expert", teacher_group=self.actor_group, actor_group=self.actor_group,
            rollout_steps=self.rollout_steps, learning_rate=self.learning_rate,
            epochs=self.epochs, minibatch_size=self.minibatch_size,
            buffer_rollouts=self.buffer_rollouts, max_grad_norm=self.max_grad_norm,
            activation=self.activation, actor_hidden=self.actor_hidden, obs_clip=self.obs_clip,
            action_noise=0.0, residual=self.residual,
        )
