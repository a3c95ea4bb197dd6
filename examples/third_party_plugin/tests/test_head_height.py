"""The example plugin proves its contract with retarget's public suite, plus its own maths."""

from __future__ import annotations

import math

from retarget_head_height import HeadHeight

from retarget import load_plugins
from retarget.testing import parametrize_with_checks


@parametrize_with_checks([HeadHeight, HeadHeight(HeadHeight.Config(k=5.0))])
def test_contract(plugin, check) -> None:
    check(plugin)


def test_plugin_is_installed() -> None:
    entry = load_plugins(strict=True).get("reward", "head_height")
    assert entry.cls is HeadHeight and entry.distribution == "retarget-head-height"


def test_value_by_hand(fake_ctx) -> None:
    ctx = fake_ctx(num_envs=3, seed=1)
    term = HeadHeight(HeadHeight.Config(k=2.0))
    term.bind(ctx.layout)
    head = ctx.layout.site("head")
    dz = float(ctx.sim.site_pos[1, head, 2] - ctx.ref.pose.site_pos[1, head, 2])
    assert math.isclose(float(term.compute(ctx)[1]), math.exp(-2.0 * abs(dz)), rel_tol=1e-6)
