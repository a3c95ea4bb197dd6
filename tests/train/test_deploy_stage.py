"""A step after an exported module (``DeployStage``): written as its own ONNX file that runs
under onnxruntime as in torch, its sidecar entry naming every input and output; a stage
whose outputs do not match its names is refused by name."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import torch

from retarget.deploy import export_stage
from retarget.errors import RetargetError
from retarget.kinds.deploy_stage import DeployStage


class _Shift(torch.nn.Module):
    def forward(self, x: torch.Tensor, by: torch.Tensor) -> torch.Tensor:
        return x * 2.0 + by[:, None]


def test_a_stage_exports_and_runs_like_torch(tmp_path: Path) -> None:
    ort = pytest.importorskip("onnxruntime")
    stage = DeployStage("shift", _Shift(), {"x": torch.ones(1, 4), "by": torch.zeros(1)},
                        ("y",), {"note": "doubles and shifts"})  # fmt: skip
    entry = export_stage(stage, tmp_path)
    assert entry == {"name": "shift", "onnx": "shift.onnx",
                     "inputs": {"x": ["batch", 4], "by": ["batch"]},
                     "outputs": {"y": ["batch", 4]}, "note": "doubles and shifts"}  # fmt: skip
    x, by = np.random.default_rng(0).normal(size=(5, 4)).astype(np.float32), np.arange(5.0)
    (y,) = ort.InferenceSession(str(tmp_path / "shift.onnx")).run(
        None, {"x": x, "by": by.astype(np.float32)})
    np.testing.assert_allclose(y, x * 2 + by[:, None], atol=1e-6)


def test_a_stage_naming_other_outputs_is_refused(tmp_path: Path) -> None:
    stage = DeployStage("shift", _Shift(), {"x": torch.ones(1, 4), "by": torch.zeros(1)},
                        ("y", "z"))  # fmt: skip
    with pytest.raises(RetargetError, match="stage 'shift' gives 1 outputs but names 2"):
        export_stage(stage, tmp_path)
    assert not (tmp_path / "shift.onnx").exists()
