"""PPO trains for real on tiny problems: it learns, is deterministic and resumes bit-for-bit."""

from __future__ import annotations

import math

import pytest
import torch
from helpers import assert_state_equal

from retarget.learn import PPOConfig, PPOLearner, torch_threads
from retarget.registry.loader import load_plugins
from retarget.testing.fakes import FakeVecEnv
from retarget.train.checkpoint import load_checkpoint, save_checkpoint

TINY = dict(
    rollout_steps=16,
    actor_hidden=(32, 32),
    critic_hidden=(32, 32),
    minibatch_size=32,
    epochs=2,
)
TIMING = {"collect_steps_per_s", "update_samples_per_s", "collect_seconds", "update_seconds"}


def learner(
    seed: int = 0, env: FakeVecEnv | None = None, num_envs: int = 8, **overrides
) -> PPOLearner:
    cfg = PPOConfig(**{**TINY, **overrides})
    env = env or FakeVecEnv(num_envs=num_envs)
    return PPOLearner(
        cfg, env.obs_dims, env.action_dim, env.num_envs, torch.Generator().manual_seed(seed)
    )


def test_learns_the_fake_task() -> None:
    env = FakeVecEnv(num_envs=32, seed=3)
    ppo = learner(
        env=env,
        num_envs=32,
        exploration_noise=0.3,
        noise_parameter="std",
        minibatch_size=128,
        epochs=5,
        learning_rate=1e-3,
    )
    first = ppo.train_iteration(env)
    for _ in range(40):
        last = ppo.train_iteration(env)
    assert all(math.isfinite(v) for v in last.values())
    assert last["mean_reward"] > first["mean_reward"] + 0.15, (first, last)
    assert last["episode_length"] == 16.0  # FakeVecEnv truncates every 16 steps


def test_stats_are_finite_and_complete() -> None:
    env = FakeVecEnv(num_envs=8)
    stats = learner(env=env).train_iteration(env)
    for key in (
        "policy_loss",
        "value_loss",
        "approx_kl",
        "clip_fraction",
        "explained_variance",
        "mean_reward",
        "episode_return",
        "episode_length",
        *TIMING,
    ):
        assert key in stats and math.isfinite(stats[key]), key


def test_first_iteration_is_bit_identical_for_a_seed() -> None:
    runs = []
    for _ in range(2):
        env = FakeVecEnv(num_envs=8, seed=5)
        ppo = learner(seed=11, env=env)
        stats = ppo.train_iteration(env)
        runs.append(({k: v for k, v in stats.items() if k not in TIMING}, ppo.state_dict()))
    assert runs[0][0] == runs[1][0]
    assert_state_equal(runs[0][1], runs[1][1])
    env = FakeVecEnv(num_envs=8, seed=5)
    other = learner(seed=12, env=env)
    other.train_iteration(env)
    assert not torch.equal(
        other.state_dict()["actor"]["net.0.weight"], runs[0][1]["actor"]["net.0.weight"]
    )


def test_resume_through_a_checkpoint_is_exact(tmp_path) -> None:
    env_a = FakeVecEnv(num_envs=8, seed=2)
    straight = learner(seed=4, env=env_a)
    for _ in range(3):
        straight.train_iteration(env_a)

    env_b = FakeVecEnv(num_envs=8, seed=2)
    first = learner(seed=4, env=env_b)
    for _ in range(2):
        first.train_iteration(env_b)
    save_checkpoint(tmp_path / "ckpt.pt", {"algorithm": first.state_dict()})
    del first
    resumed = learner(seed=999, env=env_b)  # different init: everything must come from disk
    resumed.load_state_dict(load_checkpoint(tmp_path / "ckpt.pt")["algorithm"])
    resumed.train_iteration(env_b)

    assert_state_equal(straight.state_dict(), resumed.state_dict())
    assert resumed.iteration == 3 and resumed.env_steps == 3 * 8 * 16


class TimeOutEnv(FakeVecEnv):
    """Every env times out at each step; ``final_obs`` differs from the returned obs."""

    def step(self, action):
        obs, reward, terminated, _, _ = super().step(action)
        truncated = torch.ones(self.num_envs, dtype=torch.bool)
        self.final = {k: torch.full_like(v, 3.0) for k, v in obs.items()}
        return obs, reward, terminated, truncated, {"final_obs": self.final}


def test_time_outs_bootstrap_from_final_obs() -> None:
    env = TimeOutEnv(num_envs=8)
    ppo = learner(env=env, rollout_steps=1, normalize_obs=False, normalize_values=False)
    with torch.no_grad():
        ppo.collect(env)
        want = ppo.critic(env.final["critic"])
    torch.testing.assert_close(ppo.storage.bootstrap[0], want)
    torch.testing.assert_close(ppo.storage.returns[0], ppo.storage.rewards[0] + 0.97 * want)


def test_critic_reads_the_critic_group_and_actor_the_actor_group() -> None:
    env = FakeVecEnv(num_envs=4, obs_dims={"actor": 3, "critic": 11})
    ppo = learner(env=env, num_envs=4)
    assert ppo.actor.net[0].in_features == 3
    assert ppo.critic.net[0].in_features == 11


def test_table3_defaults_and_noise_reading() -> None:
    cfg = PPOConfig()
    assert (cfg.learning_rate, cfg.gamma, cfg.lam, cfg.clip, cfg.epochs) == (
        1.2e-4,
        0.97,
        0.95,
        0.2,
        5,
    )
    assert (cfg.value_loss_coef, cfg.max_grad_norm, cfg.minibatch_size) == (0.2, 1.0, 8192)
    assert cfg.actor_hidden == (300, 200, 100) and cfg.critic_hidden == (400, 400, 300, 200)
    assert cfg.init_std == pytest.approx(math.sqrt(0.02))
    assert PPOConfig(noise_parameter="std").init_std == 0.02
    env = FakeVecEnv(num_envs=4)
    ppo = learner(env=env, num_envs=4, exploration_noise=0.02)
    assert not any(p is ppo.actor.log_std for p in ppo.params)  # fixed noise is not trained
    learned = learner(env=env, num_envs=4, learn_std=True)
    assert any(p is learned.actor.log_std for p in learned.params)


def test_act_is_deterministic_and_bounded() -> None:
    env = FakeVecEnv(num_envs=4)
    ppo = learner(env=env, num_envs=4)
    ppo.train_iteration(env)
    obs = {k: v * 100 for k, v in env.reset().items()}
    a = ppo.act(obs)
    assert torch.equal(a, ppo.act(obs))
    assert a.abs().max() <= 1.0


def test_thread_counts_are_restored() -> None:
    before = torch.get_num_threads()
    with torch_threads(1):
        assert torch.get_num_threads() == 1
    assert torch.get_num_threads() == before


def test_plugin_is_registered_with_defaults() -> None:
    entry = load_plugins(strict=True).get("algorithm", "ppo")
    algo = entry.cls()
    env = FakeVecEnv(num_envs=4)
    algo.setup(env, torch.Generator().manual_seed(0))
    # paper Table 3 defaults
    cfg = algo.config
    table3 = (1.2e-4, 0.97, 0.95, 0.2, 5)
    assert (cfg.learning_rate, cfg.gamma, cfg.lam, cfg.clip, cfg.epochs) == table3
    assert cfg.actor_hidden == (300, 200, 100) and cfg.critic_hidden == (400, 400, 300, 200)
    assert cfg.activation == "tanh"
    assert algo.act(env.reset()).shape == (4, env.action_dim)
    with pytest.raises(Exception, match="extra"):
        entry.cls.Config(no_such_field=1)
