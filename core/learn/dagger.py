"""Online distillation (DAgger): a student policy learns a frozen teacher's actions on the
states the student itself visits (SimXR, Algorithm 1).

Each iteration the *student* acts in the environment for ``rollout_steps`` steps (with a
small exploration noise, and with probability ``beta`` per environment the teacher's action
instead, early in training); the teacher labels every visited state from its own observation
group of the same environment; the student then takes supervised steps on those labels (MSE
on the action means, or the KL divergence of the two Gaussians). Supervised learning on a
teacher's labels needs far fewer samples than learning the same behaviour by reward: that is
the reason for this stage. Everything random draws from one private generator whose state is
saved, so a resumed run continues bit for bit.
"""

from __future__ import annotations

import copy
import math
import time
from collections.abc import Mapping, Sequence
from typing import Any

import torch
from torch import nn

from retarget.kinds import VecEnv
from retarget.kinds.comm import SINGLE, Comm
from retarget.learn.columns import ImageInput
from retarget.learn.config import DaggerConfig
from retarget.learn.episodes import EpisodeTracker, clone_obs
from retarget.learn.networks import GaussianActor
from retarget.learn.normalizer import GroupNormalizer
from retarget.learn.ppo import DeployedPolicy
from retarget.learn.threads import torch_threads
from retarget.learn.widen import widen_group_normalizers, widen_module


class DaggerLearner:
    """Student network, normaliser, optimiser, label buffer and counters of one DAgger run."""

    def __init__(
        self,
        config: DaggerConfig,
        obs_dims: Mapping[str, int],
        action_dim: int,
        num_envs: int,
        generator: torch.Generator | None = None,
        images: Sequence[ImageInput] = (),
        comm: Comm = SINGLE,
        residual: slice | None = None,
    ) -> None:
        """``images``: the student group's image sources (a convolutional encoder each);
        ``comm``: the ranks of a data-parallel run (see :class:`~retarget.learn.ppo.PPOLearner`);
        ``residual``: columns of the raw student observation added to the network's output
        (``algorithm.residual``), as PPO's, so a residual teacher's actor carries over."""
        self.config = c = config
        self.residual = residual
        self.comm = comm
        for group in (c.actor_group, c.teacher_group):
            if group not in obs_dims:
                raise ValueError(
                    f"the env has no {group!r} observation group ({', '.join(obs_dims)}); a "
                    "DAgger recipe is prepared with the teacher's group by `retarget train`"
                )
        seed = torch.randint(0, 2**62, (1,), generator=generator).item()
        self.generator = torch.Generator().manual_seed(int(seed))
        self.actor_key, self.teacher_key = c.actor_group, c.teacher_group
        self.num_envs, self.action_dim = num_envs, action_dim
        dim = int(obs_dims[self.actor_key])
        self.actor = GaussianActor(
            dim,
            action_dim,
            c.actor_hidden,
            activation=c.activation,
            init_std=c.teacher_std,
            learn_std=c.loss == "kl",
            generator=self.generator,
            images=images,
        )
        comm.broadcast_modules([self.actor])
        self.obs_norm = GroupNormalizer({self.actor_key: dim}, clip=c.obs_clip)
        self.optimizer = torch.optim.Adam(self.actor.parameters(), lr=c.learning_rate)
        size = c.buffer_rollouts * c.rollout_steps * num_envs
        self.buffer_obs = torch.zeros(size, dim)
        self.buffer_labels = torch.zeros(size, action_dim)
        self.buffer_fill = 0  # rows of the buffer holding samples
        self.buffer_next = 0  # next row to write
        self.teacher: nn.Module | None = None
        self.last_obs: dict[str, torch.Tensor] | None = None
        self.episodes = EpisodeTracker(num_envs, c.episode_window)
        self.iteration = 0
        self.env_steps = 0

    def set_teacher(self, teacher: nn.Module) -> None:
        """The frozen policy that labels states: raw teacher-group observations -> actions."""
        teacher = copy.deepcopy(teacher).eval()
        for p in teacher.parameters():
            p.requires_grad_(False)
        self.teacher = teacher

    # ------------------------------------------------------------------ acting

    def _normalized(self, raw: torch.Tensor) -> torch.Tensor:
        return self.obs_norm.group(self.actor_key, raw)

    def mean(self, raw: torch.Tensor) -> torch.Tensor:
        """The student's action mean (unclamped) on raw student observations: the network's
        output, plus the residual source's columns when the policy is residual."""
        out = self.actor(self._normalized(raw))
        if self.residual is not None:
            out = out + raw[:, self.residual].float()
        return out

    @torch.no_grad()
    def act(self, obs: Mapping[str, torch.Tensor]) -> torch.Tensor:
        """The student's deterministic action (its Gaussian's mean) in [-1, 1]."""
        return self.mean(obs[self.actor_key].float()).clamp(-1.0, 1.0)

    def deployable_policy(self) -> nn.Module:
        """Normaliser + student mean network + clamp, frozen: needs no teacher at run time."""
        norm = self.obs_norm.normalizer(self.actor_key)
        return DeployedPolicy(norm, self.actor, self.residual).eval()

    def beta(self) -> float:
        """Probability that the teacher acts in an environment this iteration."""
        c = self.config
        if c.beta <= 0:
            return 0.0
        if c.beta_iterations == 0:
            return c.beta
        return c.beta * max(0.0, 1.0 - self.iteration / c.beta_iterations)

    # ------------------------------------------------------------------ collection

    @torch.no_grad()
    def collect(self, env: VecEnv) -> dict[str, float]:
        c = self.config
        if self.teacher is None:
            raise RuntimeError("DaggerLearner.set_teacher(policy) must be called first")
        if self.last_obs is None:
            self.last_obs = {k: v.float() for k, v in env.reset().items()}
            norm = self.obs_norm.normalizer(self.actor_key)
            if int(norm.count) == 0:
                norm.update_ranks(self.comm, self.last_obs[self.actor_key])
        obs = self.last_obs
        pending = GroupNormalizer({self.actor_key: self.buffer_obs.shape[1]})
        teacher_acts = torch.rand(self.num_envs, generator=self.generator) < self.beta()
        gap = 0.0
        for _ in range(c.rollout_steps):
            raw = obs[self.actor_key]
            pending.update({self.actor_key: raw})
            label = self.teacher(obs[self.teacher_key])
            mean = self.mean(raw)
            gap += float((mean.clamp(-1, 1) - label).square().mean())
            noise = torch.randn(mean.shape, generator=self.generator) * c.action_noise
            action = torch.where(teacher_acts[:, None], label, mean + noise)
            self._store(raw, label)
            next_obs, reward, terminated, truncated, _ = env.step(action)
            self.episodes.step(reward.float(), terminated.bool() | truncated.bool())
            obs = {k: v.float() for k, v in next_obs.items()}
        self.last_obs = obs
        norm = self.obs_norm.normalizer(self.actor_key)
        norm.merge_ranks(self.comm, *pending.normalizer(self.actor_key).raw_stats())
        return {
            "action_gap": gap / c.rollout_steps,  # student vs teacher, on the student's states
            "beta": self.beta(),
            "episodes_finished": float(self.episodes.end_rollout()),
        }

    def _store(self, raw: torch.Tensor, label: torch.Tensor) -> None:
        n, size = raw.shape[0], self.buffer_obs.shape[0]
        rows = (self.buffer_next + torch.arange(n)) % size
        self.buffer_obs[rows] = raw
        self.buffer_labels[rows] = label
        self.buffer_next = int((self.buffer_next + n) % size)
        self.buffer_fill = min(size, self.buffer_fill + n)

    # ------------------------------------------------------------------ update

    def loss(self, raw: torch.Tensor, label: torch.Tensor) -> torch.Tensor:
        """Supervised loss of the student on raw observations against teacher actions."""
        mean = self.mean(raw)
        if self.config.loss == "mse":
            return (mean - label).square().sum(-1).mean()
        log_std = self.actor.log_std
        t_var = self.config.teacher_std**2
        kl = log_std - math.log(self.config.teacher_std) + (
            t_var + (label - mean).square()
        ) / (2 * (2 * log_std).exp()) - 0.5
        return kl.sum(-1).mean()

    def update(self) -> dict[str, float]:
        c = self.config
        total = self.buffer_fill
        count = max(1, round(total / c.minibatch_size))
        losses, n = 0.0, 0
        for _ in range(c.epochs):
            order = torch.randperm(total, generator=self.generator)
            for idx in order.chunk(count):
                loss = self.loss(self.buffer_obs[idx], self.buffer_labels[idx])
                self.optimizer.zero_grad(set_to_none=True)
                loss.backward()
                self.comm.average_gradients(list(self.actor.parameters()))
                nn.utils.clip_grad_norm_(self.actor.parameters(), c.max_grad_norm)
                self.optimizer.step()
                losses += float(loss.detach())
                n += 1
        return {"distill_loss": losses / n, "gradient_steps": float(n)}

    def train_iteration(self, env: VecEnv) -> dict[str, float]:
        """Collect ``rollout_steps`` steps with the student acting, then learn the labels."""
        c = self.config
        samples = c.rollout_steps * self.num_envs
        with torch_threads(c.collect_threads):
            t0 = time.perf_counter()
            stats = self.collect(env)
            t1 = time.perf_counter()
        with torch_threads(c.update_threads):
            stats.update(self.update())
            t2 = time.perf_counter()
        self.iteration += 1
        self.env_steps += samples
        stats["collect_steps_per_s"] = samples / max(t1 - t0, 1e-9)
        stats["update_samples_per_s"] = samples / max(t2 - t1, 1e-9)
        stats["collect_seconds"], stats["update_seconds"] = t1 - t0, t2 - t1
        stats.update(self.episodes.stats())
        return stats

    # ------------------------------------------------------------------ checkpoints

    def fresh_rank(self, generator: torch.Generator) -> None:
        """Forget rank 0's environment (a rank added on resume): own noise, a fresh rollout
        start and episode counters (the label buffer stays: its labels are still right)."""
        seed = torch.randint(0, 2**62, (1,), generator=generator).item()
        self.generator.manual_seed(int(seed))
        self.last_obs = None
        self.episodes = EpisodeTracker(self.num_envs, self.config.episode_window)

    def warm_start(self, state: Mapping[str, Any], inputs: Mapping[str, torch.Tensor]) -> None:
        """The student network and its observation statistics from another run's
        :meth:`state_dict` (a student, or a PPO run's actor), input columns remapped by
        ``inputs``; optimiser, label buffer and counters start fresh.

        A student distilled from one teacher is re-distilled from a better one, or on more
        motions, in a fraction of the samples it took from scratch."""
        widen_module(self.actor, state["actor"], inputs[self.actor_key])
        count = 10.0 * self.config.rollout_steps * self.num_envs  # as PPO's warm start
        widen_group_normalizers(self.obs_norm.groups, state["obs_norm"], inputs, count)
        self.last_obs = None

    def state_dict(self) -> dict[str, Any]:
        """Everything a bit-exact resume needs (the teacher is reloaded from its run)."""
        keep = self.config.buffer_rollouts > 1  # with one rollout the buffer is refilled first
        return {
            "actor": self.actor.state_dict(),
            "obs_norm": self.obs_norm.state_dict(),
            "optimizer": self.optimizer.state_dict(),
            "generator": self.generator.get_state(),
            "buffer": {
                "obs": self.buffer_obs.clone() if keep else None,
                "labels": self.buffer_labels.clone() if keep else None,
                "fill": self.buffer_fill if keep else 0,
                "next": self.buffer_next if keep else 0,
            },
            "last_obs": clone_obs(self.last_obs),
            **self.episodes.state_dict(),
            "iteration": self.iteration,
            "env_steps": self.env_steps,
        }

    def load_state_dict(self, state: Mapping[str, Any]) -> None:
        self.actor.load_state_dict(state["actor"])
        if "optimizer" not in state:  # a policy-only checkpoint (pretrained): acting only
            self.obs_norm.load_state_dict(state["obs_norm"])
            self.last_obs = None
            return
        self.obs_norm.load_state_dict(state["obs_norm"])
        self.optimizer.load_state_dict(state["optimizer"])
        self.generator.set_state(state["generator"])
        buffer = state["buffer"]
        if buffer["obs"] is not None and buffer["obs"].shape == self.buffer_obs.shape:
            self.buffer_obs.copy_(buffer["obs"])
            self.buffer_labels.copy_(buffer["labels"])
            self.buffer_fill, self.buffer_next = int(buffer["fill"]), int(buffer["next"])
        else:
            self.buffer_fill = self.buffer_next = 0
        self.last_obs = clone_obs(state["last_obs"])
        if not self.episodes.load_state_dict(state):  # another env count: only the policy
            self.last_obs = None
        self.iteration = int(state["iteration"])
        self.env_steps = int(state["env_steps"])
