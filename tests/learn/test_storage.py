"""GAE: failures end the return, time-outs bootstrap from the observation they ended in."""

from __future__ import annotations

import torch

from retarget.learn import RolloutStorage, gae


def reference_gae(rewards, values, last, term, trunc, boot, gamma, lam):
    """Per-environment textbook recursion, written independently of the batched one."""
    steps, envs = rewards.shape
    out = torch.zeros(steps, envs)
    for n in range(envs):
        acc = 0.0
        for t in reversed(range(steps)):
            if term[t, n]:
                delta, acc = rewards[t, n] - values[t, n], 0.0
            elif trunc[t, n]:
                delta, acc = rewards[t, n] + gamma * boot[t, n] - values[t, n], 0.0
            else:
                nxt = last[n] if t == steps - 1 else values[t + 1, n]
                delta = rewards[t, n] + gamma * nxt - values[t, n]
            acc = float(delta + gamma * lam * acc)
            out[t, n] = acc
    return out


def test_gae_matches_reference_with_mixed_endings() -> None:
    g = torch.Generator().manual_seed(0)
    steps, envs = 12, 5
    rewards = torch.rand(steps, envs, generator=g)
    values = torch.randn(steps, envs, generator=g)
    last = torch.randn(envs, generator=g)
    term = torch.rand(steps, envs, generator=g) < 0.15
    trunc = (torch.rand(steps, envs, generator=g) < 0.15) & ~term
    boot = torch.where(trunc, torch.randn(steps, envs, generator=g), 0.0)
    got = gae(rewards, values, last, term, trunc, boot, 0.97, 0.95)
    want = reference_gae(rewards, values, last, term, trunc, boot, 0.97, 0.95)
    torch.testing.assert_close(got, want, rtol=1e-5, atol=1e-5)


def test_failure_and_timeout_differ_only_by_the_bootstrap() -> None:
    rewards = torch.ones(1, 1)
    values = torch.zeros(1, 1)
    last = torch.full((1,), 100.0)  # the next episode's value must never leak in
    boot = torch.full((1, 1), 10.0)
    yes, no = torch.ones(1, 1, dtype=torch.bool), torch.zeros(1, 1, dtype=torch.bool)
    failed = gae(rewards, values, last, yes, no, boot, 0.5, 0.9)
    timed_out = gae(rewards, values, last, no, yes, boot, 0.5, 0.9)
    assert failed.item() == 1.0
    assert timed_out.item() == 1.0 + 0.5 * 10.0


def test_minibatches_cover_every_sample_once() -> None:
    st = RolloutStorage(4, 3, {"actor": 2}, 1)
    st.obs["actor"].copy_(torch.arange(24.0).reshape(4, 3, 2))
    seen = torch.cat([mb["obs/actor"][:, 0] for mb in st.minibatches(5, torch.Generator())])
    assert sorted(seen.tolist()) == list(range(0, 24, 2))
