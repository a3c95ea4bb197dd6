"""PPO with an asymmetric critic: collection, GAE and the clipped update.

The actor reads the ``actor`` observation group (what a headset user can provide); the critic
reads ``critic`` (privileged simulation state), which only training needs. Everything random
(weight init, action noise, minibatch order) draws from one private ``torch.Generator``
seeded from the one given to :meth:`PPOLearner.__init__`, and its state is part of
:meth:`state_dict`, so a resumed run continues bit-for-bit.

Environment contract used here (see :class:`retarget.kinds.VecEnv`): ``step`` auto-resets
finished environments, and when some were *truncated* (time limit, clip end) it may return
``info["final_obs"]``: a mapping group -> ``(N, D)`` whose rows for the truncated environments
hold the observation they ended in (other rows are ignored). Their value is bootstrapped from
it. Without that key, truncated environments are bootstrapped from the returned (already
reset) observation, an approximation that is exact only when observations do not depend on
the episode (as in ``FakeVecEnv``).
"""

from __future__ import annotations

import copy
import time
from collections.abc import Mapping, Sequence
from typing import Any

import torch
from torch import nn

from retarget.kinds import VecEnv
from retarget.kinds.comm import SINGLE, Comm
from retarget.learn.columns import ImageInput
from retarget.learn.config import PPOConfig
from retarget.learn.episodes import EpisodeTracker, clone_obs
from retarget.learn.networks import Critic, GaussianActor
from retarget.learn.normalizer import GroupNormalizer, RunningNormalizer
from retarget.learn.overlap import OverlapState
from retarget.learn.storage import RolloutStorage
from retarget.learn.threads import torch_threads
from retarget.learn.widen import widen_group_normalizers, widen_module


class DeployedPolicy(nn.Module):
    """Raw actor observations -> actions in [-1, 1]: what a headset application runs.

    Frozen copies of the actor's normaliser and mean network (its image encoder included), so
    it computes exactly what
    :meth:`PPOLearner.act` does at export time and later training does not change it.
    """

    def __init__(
        self,
        normalizer: RunningNormalizer | None,
        net: nn.Module,
        residual: slice | None = None,
    ) -> None:
        super().__init__()
        self.norm = copy.deepcopy(normalizer) if normalizer is not None else nn.Identity()
        self.net = copy.deepcopy(net)
        self.base = (residual.start, residual.stop) if residual is not None else None

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        out = self.net(self.norm(obs))
        if self.base is not None:
            out = out + obs[:, self.base[0] : self.base[1]]
        return out.clamp(-1.0, 1.0)


class PPOLearner:
    """Networks, optimiser, normalisers, storage and counters of one PPO run."""

    def __init__(
        self,
        config: PPOConfig,
        obs_dims: Mapping[str, int],
        action_dim: int,
        num_envs: int,
        generator: torch.Generator | None = None,
        residual: slice | None = None,
        images: Mapping[str, Sequence[ImageInput]] | None = None,
        comm: Comm = SINGLE,
    ) -> None:
        """``residual``: columns of the raw actor observation added to the network's output
        (the policy's actions are that base plus a learned, explored residual); ``images``:
        per group, its image sources, which get a convolutional encoder; ``comm``: the ranks
        of a data-parallel run (weights from rank 0, gradients averaged, statistics merged)."""
        self.config = c = config
        self.comm = comm
        self.residual = residual
        seed = torch.randint(0, 2**62, (1,), generator=generator).item()
        self.generator = torch.Generator().manual_seed(int(seed))
        if c.actor_group not in obs_dims:
            raise ValueError(f"the env has no {c.actor_group!r} observation group: {obs_dims}")
        self.actor_key = c.actor_group
        # without a privileged group the critic sees what the actor sees (symmetric PPO)
        self.critic_key = c.critic_group if c.critic_group in obs_dims else c.actor_group
        dims = {k: int(obs_dims[k]) for k in dict.fromkeys((self.actor_key, self.critic_key))}
        self.num_envs, self.action_dim = num_envs, action_dim
        self.actor = GaussianActor(
            dims[self.actor_key],
            action_dim,
            c.actor_hidden,
            activation=c.activation,
            init_std=c.init_std,
            learn_std=c.learn_std,
            generator=self.generator,
            images=(images or {}).get(self.actor_key, ()),
        )
        self.critic = Critic(
            dims[self.critic_key],
            c.critic_hidden,
            activation=c.activation,
            generator=self.generator,
            images=(images or {}).get(self.critic_key, ()),
        )
        comm.broadcast_modules([self.actor, self.critic])
        self.obs_norm = GroupNormalizer(dims, clip=c.obs_clip)
        # return statistics follow the improving policy: ~20 iterations of memory
        samples = c.rollout_steps * num_envs
        self.value_norm = RunningNormalizer(1, clip=float("inf"), max_count=20.0 * samples)
        params = [*self.actor.parameters(), *self.critic.parameters()]
        self.params = params
        self.optimizer = torch.optim.Adam(params, lr=c.learning_rate)
        self.storage = RolloutStorage(c.rollout_steps, num_envs, dims, action_dim)
        self.last_obs: dict[str, torch.Tensor] | None = None
        self.episodes = EpisodeTracker(num_envs, c.episode_window)
        self._pending: tuple[GroupNormalizer, RolloutStorage] | None = None
        self.overlap = OverlapState(self) if c.overlap else None
        self.iteration = 0
        self.env_steps = 0

    # ------------------------------------------------------------------ helpers

    def _normalize(self, key: str, x: torch.Tensor, nets: Any = None) -> torch.Tensor:
        norm = (nets or self).obs_norm
        return norm.group(key, x) if self.config.normalize_obs else x

    def _value(self, critic_obs: torch.Tensor, nets: Any = None) -> torch.Tensor:
        """Value in reward units of already-normalised critic observations (of ``nets``'
        critic: the learner's own, or the acting copy of an overlapped iteration)."""
        n = nets or self
        v = n.critic(critic_obs)
        if self.config.normalize_values:
            v = v * n.value_norm.var.sqrt().float() + n.value_norm.mean.float()
        return v

    def _base(self, raw_actor_obs: torch.Tensor) -> torch.Tensor | float:
        """What the policy's output is added to: the residual source's raw columns, or 0."""
        if self.residual is None:
            return 0.0
        return raw_actor_obs[:, self.residual].float()

    @torch.no_grad()
    def act(self, obs: Mapping[str, torch.Tensor]) -> torch.Tensor:
        """The deterministic policy (the Gaussian's mean) in [-1, 1]."""
        raw = obs[self.actor_key].float()
        x = self._normalize(self.actor_key, raw)
        return (self.actor(x) + self._base(raw)).clamp(-1.0, 1.0)

    def deployable_policy(self) -> nn.Module:
        """A frozen copy of :meth:`act` as one module (normaliser + mean network + clamp)."""
        norm = self.obs_norm.normalizer(self.actor_key) if self.config.normalize_obs else None
        return DeployedPolicy(norm, self.actor, self.residual).eval()

    # ------------------------------------------------------------------ collection

    @torch.no_grad()
    def collect(
        self,
        env: VecEnv,
        nets: Any = None,
        storage: RolloutStorage | None = None,
        absorb: bool = True,
    ) -> dict[str, float]:
        """One rollout into ``storage`` (default: the learner's), acting with ``nets`` (default:
        the learner's own networks and statistics). With ``absorb`` its observation and return
        statistics are merged into the learner's at once; without, they wait for
        :meth:`absorb` (an overlapped iteration merges them after the concurrent update)."""
        c = self.config
        st = storage if storage is not None else self.storage
        if self.last_obs is None:
            self.last_obs = {k: v.float() for k, v in env.reset().items()}
            if c.normalize_obs:  # groups without statistics yet start from these
                for key, norm in self.obs_norm.groups.items():
                    if int(norm.count) == 0:
                        norm.update_ranks(self.comm, self.last_obs[key])
        obs = self.last_obs
        st.clear()
        actor = (nets or self).actor
        std = actor.std()
        term_sums: dict[str, float] = {}  # per reward term: episode sums x finished episodes
        term_count = 0.0
        # raw observation statistics of this rollout, merged into the normaliser at its end
        pending = GroupNormalizer({k: v.shape[-1] for k, v in st.obs.items()})
        for _ in range(c.rollout_steps):
            if c.normalize_obs:
                pending.update(obs)
            a_obs = self._normalize(self.actor_key, obs[self.actor_key], nets)
            c_obs = self._normalize(self.critic_key, obs[self.critic_key], nets)
            mean = actor(a_obs)
            noise = torch.randn(mean.shape, generator=self.generator)
            action = mean + noise * std  # a residual when ``residual`` is set
            log_prob = actor.log_prob(mean, action)
            value = self._value(c_obs, nets)
            next_obs, reward, terminated, truncated, info = env.step(
                action + self._base(obs[self.actor_key])
            )
            reward = reward.float()
            terminated, truncated = terminated.bool(), truncated.bool() & ~terminated.bool()
            bootstrap = None
            if truncated.any():
                final = info.get("final_obs", next_obs)[self.critic_key].float()
                bootstrap = torch.where(
                    truncated, self._value(self._normalize(self.critic_key, final, nets), nets),
                    0.0,
                )
            st.add(
                {self.actor_key: a_obs, self.critic_key: c_obs},
                action,
                log_prob,
                value,
                reward,
                terminated,
                truncated,
                bootstrap,
            )
            self.episodes.step(reward, terminated | truncated)
            episode = info.get("episode")
            if episode is not None and "terms" in episode:
                weight = float(episode["length"].numel())
                for name, value in episode["terms"].items():
                    term_sums[name] = term_sums.get(name, 0.0) + float(value) * weight
                term_count += weight
            obs = {k: v.float() for k, v in next_obs.items()}
        self.last_obs = obs
        last_values = self._value(
            self._normalize(self.critic_key, obs[self.critic_key], nets), nets
        )
        st.compute_returns(last_values, c.gamma, c.lam)
        self._pending = (pending, st)
        if absorb:
            self.absorb()
        stats = {
            "mean_reward": float(st.rewards.mean()),
            "episodes_finished": float(self.episodes.end_rollout()),
        }
        if term_count:  # mean episode sum of each reward term (the env's info["episode"])
            stats.update({f"episode_{k}": v / term_count for k, v in term_sums.items()})
        return stats

    @torch.no_grad()
    def absorb(self) -> None:
        """Merge the last rollout's observation statistics and returns into the learner's
        normalisers (PopArt keeps the critic's predictions in reward units)."""
        if self._pending is None:
            return
        pending, st = self._pending
        self._pending = None
        if self.config.normalize_obs:
            for key, norm in self.obs_norm.groups.items():
                norm.merge_ranks(self.comm, *pending.normalizer(key).raw_stats())
        if self.config.normalize_values:
            self._update_value_stats(st.returns)

    @torch.no_grad()
    def _update_value_stats(self, returns: torch.Tensor) -> None:
        """Move the return statistics and rescale the critic's output layer so that its
        predictions in reward units do not change (PopArt): the stored values of this
        rollout stay consistent with the critic the update starts from."""
        norm = self.value_norm
        old_mean, old_std = norm.mean.clone(), norm.var.sqrt()
        norm.update_ranks(self.comm, returns.reshape(-1, 1))
        new_mean, new_std = norm.mean, norm.var.sqrt()
        last = self.critic.net[-1]
        assert isinstance(last, nn.Linear)
        last.weight.mul_((old_std / new_std).float())
        last.bias.copy_(((old_std * last.bias.double() + old_mean - new_mean) / new_std).float())

    # ------------------------------------------------------------------ update

    def update(
        self,
        storage: RolloutStorage | None = None,
        generator: torch.Generator | None = None,
        proximal: bool = False,
    ) -> dict[str, float]:
        """The clipped PPO update on ``storage`` (default: the learner's last rollout),
        minibatches drawn from ``generator`` (default: the learner's).

        ``proximal``: the rollout came from an older policy than the one updated (an
        overlapped iteration), so the objective is decoupled (Hilton et al. 2022, "Batch
        size-invariance for policy optimization"): the ratio is clipped around the policy this
        update starts from, and each sample is weighted by that policy's probability over the
        behaviour policy's, instead of clipping around the stale behaviour policy."""
        c = self.config
        st = storage if storage is not None else self.storage
        if c.normalize_advantages:
            adv = st.advantages
            st.advantages.copy_((adv - adv.mean()) / (adv.std() + 1e-8))
        total = st.steps * st.num_envs
        count = max(1, round(total / c.minibatch_size))
        extra = {}
        if proximal:
            with torch.no_grad():
                obs = st.obs[self.actor_key].reshape(total, -1)
                actions = st.actions.reshape(total, -1)
                extra["prox"] = self.actor.log_prob(self.actor(obs), actions)
        sums = dict.fromkeys(("policy_loss", "value_loss", "approx_kl", "clip_fraction"), 0.0)
        grad_norm, n = 0.0, 0
        v_mean, v_std = self.value_norm.mean.float(), self.value_norm.var.sqrt().float()
        for _ in range(c.epochs):
            for mb in st.minibatches(count, generator or self.generator, extra):
                mean = self.actor(mb[f"obs/{self.actor_key}"])
                log_prob = self.actor.log_prob(mean, mb["actions"])
                anchor = mb.get("prox", mb["log_probs"])
                log_ratio = log_prob - anchor
                ratio = log_ratio.exp()
                adv = mb["advantages"]
                surrogate = torch.min(ratio * adv, ratio.clamp(1 - c.clip, 1 + c.clip) * adv)
                if "prox" in mb:  # importance of the proximal policy over the behaviour one
                    surrogate = surrogate * (mb["prox"] - mb["log_probs"]).exp()
                policy_loss = -surrogate.mean()
                value, old, target = (
                    self.critic(mb[f"obs/{self.critic_key}"]),
                    mb["values"],
                    mb["returns"],
                )
                if c.normalize_values:
                    old, target = (old - v_mean) / v_std, (target - v_mean) / v_std
                value_loss = (value - target).square()
                if c.value_clip is not None:
                    clipped = old + (value - old).clamp(-c.value_clip, c.value_clip)
                    value_loss = torch.max(value_loss, (clipped - target).square())
                value_loss = value_loss.mean()
                loss = c.value_loss_coef * value_loss
                if self.iteration >= c.critic_warmup:  # else only the critic learns
                    loss = loss + policy_loss
                if c.entropy_coef:
                    loss = loss - c.entropy_coef * self.actor.entropy()
                self.optimizer.zero_grad(set_to_none=True)
                loss.backward()
                self.comm.average_gradients(self.params)
                grad_norm += float(nn.utils.clip_grad_norm_(self.params, c.max_grad_norm))
                self.optimizer.step()
                with torch.no_grad():
                    sums["policy_loss"] += float(policy_loss)
                    sums["value_loss"] += float(value_loss)
                    sums["approx_kl"] += float(((ratio - 1) - log_ratio).mean())
                    sums["clip_fraction"] += float(((ratio - 1).abs() > c.clip).float().mean())
                n += 1
        stats = {k: v / n for k, v in sums.items()}
        stats["grad_norm"] = grad_norm / n
        stats["gradient_steps"] = float(n)
        return stats

    def explained_variance(self) -> float:
        """1 - Var(returns - values) / Var(returns) of the rollout just collected."""
        returns, values = self.storage.returns, self.storage.values
        var = float(returns.var())
        return float(1.0 - (returns - values).var() / var) if var > 1e-12 else 0.0

    def train_iteration(self, env: VecEnv) -> dict[str, float]:
        """Collect ``rollout_steps`` steps from ``env`` and run the PPO update on them (with
        ``overlap``: update on the previous rollout while this one is collected)."""
        if self.overlap is not None:
            return self.overlap.iteration(env)
        c = self.config
        samples = c.rollout_steps * self.num_envs
        with torch_threads(c.collect_threads):
            t0 = time.perf_counter()
            stats = self.collect(env)
            t1 = time.perf_counter()
        explained = self.explained_variance()
        with torch_threads(c.update_threads):
            t2 = time.perf_counter()
            stats.update(self.update())
            t3 = time.perf_counter()
        self.iteration += 1
        self.env_steps += samples
        stats["explained_variance"] = explained
        stats["action_std"] = float(self.actor.std().mean())
        stats["collect_steps_per_s"] = samples / max(t1 - t0, 1e-9)
        stats["update_samples_per_s"] = samples / max(t3 - t2, 1e-9)
        stats["collect_seconds"] = t1 - t0
        stats["update_seconds"] = t3 - t2
        stats.update(self.episodes.stats())
        return stats

    # ------------------------------------------------------------------ checkpoints

    def state_dict(self) -> dict[str, Any]:
        """Everything a bit-exact resume needs (the env's own state is saved by its owner)."""
        return {
            "actor": self.actor.state_dict(),
            "critic": self.critic.state_dict(),
            "obs_norm": self.obs_norm.state_dict(),
            "value_norm": self.value_norm.state_dict(),
            "optimizer": self.optimizer.state_dict(),
            "generator": self.generator.get_state(),
            "last_obs": clone_obs(self.last_obs),
            **self.episodes.state_dict(),
            "iteration": self.iteration,
            "env_steps": self.env_steps,
            **({"overlap": self.overlap.state_dict()} if self.overlap is not None else {}),
        }

    def load_state_dict(self, state: Mapping[str, Any]) -> None:
        self.actor.load_state_dict(state["actor"])
        if "optimizer" not in state:  # a policy-only checkpoint (pretrained): acting only
            self.obs_norm.load_state_dict(state["obs_norm"])
            if "critic" in state:
                self.critic.load_state_dict(state["critic"])
                self.value_norm.load_state_dict(state["value_norm"])
            self.last_obs = None
            return
        self.critic.load_state_dict(state["critic"])
        self.obs_norm.load_state_dict(state["obs_norm"])
        self.value_norm.load_state_dict(state["value_norm"])
        self.optimizer.load_state_dict(state["optimizer"])
        self.generator.set_state(state["generator"])
        self.last_obs = clone_obs(state["last_obs"])
        if not self.episodes.load_state_dict(state):  # another env count: only the policy
            self.last_obs = None
        self.iteration = int(state["iteration"])
        self.env_steps = int(state["env_steps"])
        if self.overlap is not None:
            self.overlap.load_state_dict(state.get("overlap") if self.last_obs is not None
                                         else None)  # fmt: skip

    def fresh_rank(self, generator: torch.Generator) -> None:
        """Forget rank 0's environment (a rank added on resume): its own noise, a fresh
        rollout start and episode counters."""
        seed = torch.randint(0, 2**62, (1,), generator=generator).item()
        self.generator.manual_seed(int(seed))
        self.last_obs = None
        self.episodes = EpisodeTracker(self.num_envs, self.config.episode_window)
        if self.overlap is not None:  # rank 0's waiting rollout is rank 0's to learn from
            self.overlap.load_state_dict(None)

    def warm_start(self, state: Mapping[str, Any], inputs: Mapping[str, torch.Tensor]) -> None:
        """Networks and observation statistics from another run's :meth:`state_dict`, input
        columns remapped by ``inputs`` (see :mod:`retarget.learn.widen`); the optimiser and
        the counters start fresh, so this is a new run, not a resume.

        A source without a critic (a distilled student) gives the actor only: the critic and
        its statistics start fresh, which ``critic_warmup`` iterations then train alone."""
        widen_module(self.actor, state["actor"], inputs[self.actor_key])
        if "critic" in state:
            widen_module(self.critic, state["critic"], inputs[self.critic_key])
            self.value_norm.load_state_dict(state["value_norm"])
        # the kept inputs' statistics are frozen (the weights were learned with them); the
        # whole counts as ten rollouts, so new inputs find their scale in a few iterations
        count = 10.0 * self.config.rollout_steps * self.num_envs
        widen_group_normalizers(self.obs_norm.groups, state["obs_norm"], inputs, count)
        self.last_obs = None
