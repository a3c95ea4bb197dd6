"""Running statistics equal the statistics of all data seen, and survive a state_dict."""

from __future__ import annotations

import torch

from retarget.learn import GroupNormalizer, RunningNormalizer


def test_running_stats_equal_batch_stats() -> None:
    g = torch.Generator().manual_seed(0)
    chunks = [torch.randn(n, 3, generator=g) * 5 + 2 for n in (1, 7, 100, 33)]
    norm = RunningNormalizer(3)
    for chunk in chunks:
        norm.update(chunk)
    whole = torch.cat(chunks).double()
    torch.testing.assert_close(norm.mean, whole.mean(0))
    torch.testing.assert_close(norm.var, whole.var(0, unbiased=False))
    assert norm.count.item() == whole.shape[0]
    scaled = norm(whole.float())
    torch.testing.assert_close(scaled.mean(0), torch.zeros(3), atol=1e-4, rtol=0)


def test_clip_and_saturating_count() -> None:
    norm = RunningNormalizer(1, clip=2.0, max_count=10.0)
    norm.update(torch.zeros(100, 1))
    assert norm.count.item() == 10.0
    norm.update(torch.ones(10, 1))
    assert abs(norm.mean.item() - 0.5) < 1e-12  # the old 100 samples weigh as 10
    assert norm(torch.tensor([[1e6]])).item() == 2.0


def test_group_state_dict_round_trip() -> None:
    a = GroupNormalizer({"actor": 2, "critic": 4})
    a.update({"actor": torch.randn(9, 2), "critic": torch.randn(9, 4)})
    b = GroupNormalizer({"actor": 2, "critic": 4})
    b.load_state_dict(a.state_dict())
    x = {"actor": torch.randn(3, 2), "critic": torch.randn(3, 4)}
    for key in x:
        assert torch.equal(a(x)[key], b(x)[key])
