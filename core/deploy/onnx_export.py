"""The trained actor as an ONNX file, normaliser included, plus a JSON sidecar describing its
input and output, so a headset application can run it without Python or retarget.

The graph is ``obs (B, D) float32 -> action (B, A) float32 in [-1, 1]``; actions scale to
torques by the sidecar's ``torque_limits`` (N·m, per actuator, in actuator order), exactly as
the environment applies them. The sidecar also lists the observation layout (sources and
widths, in order) and the control rate, which the application must reproduce.
"""

from __future__ import annotations

import json
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import torch

from retarget.errors import RetargetError
from retarget.kinds import Algorithm
from retarget.kinds.capabilities import Exportable

OPSET = 17


@dataclass
class ExportedPolicy:
    onnx: Path
    metadata: Path
    obs_dim: int
    action_dim: int


def policy_of(algorithm: Algorithm) -> tuple[str, torch.nn.Module]:
    """The algorithm's deployable ``(group, module)``; a user error if it has none."""
    if not isinstance(algorithm, Exportable):
        raise RetargetError(f"algorithm '{algorithm.name}' does not provide an exportable policy",
                            plugin=algorithm.name)  # fmt: skip
    return algorithm.policy()


def export_onnx(
    algorithm: Algorithm, out: Path, metadata: dict[str, Any] | None = None
) -> ExportedPolicy:
    """Write ``out`` (ONNX, dynamic batch) and ``out.with_suffix('.json')`` (metadata)."""
    group, module = policy_of(algorithm)
    module = module.eval()
    obs_dim = int(metadata["obs_dim"]) if metadata and "obs_dim" in metadata else None
    if obs_dim is None:
        first = next(p for p in module.parameters())
        obs_dim = int(first.shape[-1])
    example = torch.zeros(1, obs_dim)
    with torch.no_grad():
        action_dim = int(module(example).shape[-1])
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(out.name + ".tmp")
    with warnings.catch_warnings():  # the TorchScript-based exporter warns it is legacy
        warnings.simplefilter("ignore")
        torch.onnx.export(
            module,
            (example,),
            str(tmp),
            input_names=["obs"],
            output_names=["action"],
            dynamic_axes={"obs": {0: "batch"}, "action": {0: "batch"}},
            opset_version=OPSET,
            dynamo=False,
        )
    tmp.replace(out)
    meta = {
        "format": "retarget-policy/1",
        "observation_group": group,
        "obs_dim": obs_dim,
        "action_dim": action_dim,
        "inputs": {"obs": ["batch", obs_dim]},
        "outputs": {"action": ["batch", action_dim]},
        **(metadata or {}),
    }
    side = out.with_suffix(".json")
    side.write_text(json.dumps(meta, indent=2))
    return ExportedPolicy(out, side, obs_dim, action_dim)
