"""Both simulator backends behind ``BatchedSim`` pass the environment contract checks, and
MuJoCo Warp agrees with MuJoCo's C engine on a control step from the same state. The Warp
half is skipped where ``mujoco-warp`` is not installed (``pip install 'retarget[warp]'``);
on a CPU its kernels compile once (about a minute, cached by Warp) and then run slowly."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest
import torch
from helpers import TINY

from retarget.env.build import env_from_recipe
from retarget.errors import RetargetError
from retarget.recipe import load
from retarget.registry.loader import load_plugins
from retarget.testing.env_checks import check_env

HAVE_WARP = importlib.util.find_spec("mujoco_warp") is not None
needs_warp = pytest.mark.skipif(
    not HAVE_WARP, reason="mujoco-warp is not installed (pip install 'retarget[warp]')"
)


def _env(tmp_path: Path, backend: str, num_envs: int = 4):
    registry = load_plugins()
    recipe = tmp_path / "tiny.yaml"
    recipe.write_text(TINY)
    resolved = load(recipe, registry, assignments=[f"sim.backend={backend}"])
    return env_from_recipe(resolved, num_envs=num_envs, registry=registry)


@pytest.mark.parametrize("backend", ["mujoco", pytest.param("warp", marks=needs_warp)])
def test_backend_passes_the_env_checks(tmp_path: Path, backend: str) -> None:
    check_env(lambda: _env(tmp_path, backend))


@needs_warp
def test_warp_agrees_with_c_on_a_control_step(tmp_path: Path) -> None:
    warp, c = _env(tmp_path, "warp"), _env(tmp_path, "mujoco")
    assert type(warp.sim).__name__ == "WarpSim" and type(c.sim).__name__ == "BatchedSim"
    clip = torch.zeros(4, dtype=torch.long)
    frame = torch.tensor([2, 9, 16, 23])
    for env in (warp, c):
        env.place(clip, frame)
    action = (torch.rand(4, c.action_dim, generator=torch.Generator().manual_seed(0)) - 0.5) * 0.6
    (ow, rw, *_), (oc, rc, *_) = warp.step(action), c.step(action)
    a, b = warp.sim.state, c.sim.state
    # float32 (Warp) against float64 (C): one 10-substep control step
    assert float((a.qpos - b.qpos).abs().max()) < 1e-4
    assert float((a.qvel - b.qvel).abs().max()) < 1e-2
    assert float((a.body_pos - b.body_pos).abs().max()) < 1e-4
    assert float((a.contact_force - b.contact_force).abs().max()) < 0.5  # newtons
    assert float((rw - rc).abs().max()) < 1e-3
    for group in oc:
        assert float((ow[group] - oc[group]).abs().max()) < 0.05, group


def test_unknown_or_missing_backend_is_a_clear_error(tmp_path: Path) -> None:
    with pytest.raises(RetargetError, match=r"sim\.backend"):
        _env(tmp_path, "bullet")
    if not HAVE_WARP:
        with pytest.raises(RetargetError, match="retarget\\[warp\\]"):
            _env(tmp_path, "warp")
