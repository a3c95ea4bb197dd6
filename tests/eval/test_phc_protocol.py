"""PHC's success rule and error family on hand-made trajectories."""

from __future__ import annotations

import math
from types import SimpleNamespace

import torch

from retarget.eval.phc import PhcProtocol
from retarget.eval.terms import EvalBatch, EvalStep


def _step(sim: torch.Tensor, ref: torch.Tensor, step: int) -> EvalStep:
    ctx = SimpleNamespace(sim=SimpleNamespace(body_pos=sim),
                          ref=SimpleNamespace(pose=SimpleNamespace(body_pos=ref)))  # fmt: skip
    alive = torch.ones(sim.shape[0], dtype=torch.bool)
    return EvalStep(ctx=ctx, metrics=None, step=step, alive=alive, ok=alive)  # type: ignore[arg-type]


def _run(offsets: list[torch.Tensor]) -> dict:
    term = PhcProtocol()
    term.start(2)
    gen = torch.Generator().manual_seed(0)
    for t, offset in enumerate(offsets):
        ref = torch.randn(2, 5, 3, generator=gen) + t * 0.03
        term.update(_step(ref + offset, ref, t))
    n = len(offsets)
    batch = EvalBatch(runs=2, available=torch.full((2,), n), failed_at=torch.full((2,), n + 1.0),
                      tracked=torch.full((2,), float(n)), dt=1 / 36)  # fmt: skip
    return term.finish(batch)


def test_a_constant_offset_is_global_error_only_and_a_far_frame_fails() -> None:
    shift = torch.zeros(2, 5, 3)
    shift[:, :, 0] = 0.1  # every body 10 cm off: no root-relative, velocity or accel error
    far = shift.clone()
    far[1, :, 0] = 0.6  # run 1 is 60 cm off at one frame: a PHC failure
    out = _run([shift, shift, far, shift, shift])
    assert list(out["phc_success"]) == [1.0, 0.0]
    assert abs(out["phc_g_mpjpe"][0] - 0.1) < 1e-6
    assert out["phc_mpjpe"][0] < 1e-6 and out["phc_pa_mpjpe"][0] < 1e-4
    assert out["phc_vel"][0] < 1e-6 and out["phc_accel"][0] < 1e-6
    assert out["phc_vel"][1] > 0.1 and out["phc_accel"][1] > 0.2  # the jump and back
    assert math.isnan(out["phc_g_mpjpe_succ"][1]) and not math.isnan(out["phc_g_mpjpe"][1])


def test_a_wrong_limb_is_root_relative_error() -> None:
    bent = torch.zeros(2, 5, 3)
    bent[:, 3, 2] = 0.2  # one body of five 20 cm off
    out = _run([bent] * 4)
    assert abs(out["phc_mpjpe"][0] - 0.04) < 1e-6 and out["phc_success"][0] == 1.0
