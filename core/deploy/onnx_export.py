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
from retarget.kinds.capabilities import Exportable, PostStaged
from retarget.kinds.deploy_stage import DeployStage

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


def export_stage(stage: DeployStage, folder: Path) -> dict[str, Any]:
    """Write ``folder/NAME.onnx`` (dynamic batch on every input and output) and return its
    sidecar entry: file, inputs and outputs with their shapes, the stage's description."""
    folder.mkdir(parents=True, exist_ok=True)
    target = folder / f"{stage.name}.onnx"
    examples = tuple(stage.inputs.values())
    with torch.no_grad():
        results = stage.module.eval()(*examples)
    results = results if isinstance(results, tuple) else (results,)
    if len(results) != len(stage.outputs):
        raise RetargetError(f"stage '{stage.name}' gives {len(results)} outputs but names "
                            f"{len(stage.outputs)}")  # fmt: skip
    names = [*stage.inputs, *stage.outputs]
    tmp = target.with_name(target.name + ".tmp")
    with warnings.catch_warnings():  # the TorchScript-based exporter warns it is legacy
        warnings.simplefilter("ignore")
        torch.onnx.export(stage.module, examples, str(tmp), input_names=list(stage.inputs),
                          output_names=list(stage.outputs),
                          dynamic_axes={n: {0: "batch"} for n in names},
                          opset_version=OPSET, dynamo=False)  # fmt: skip
    tmp.replace(target)

    def shapes(tensors) -> dict[str, list[str | int]]:
        return {n: ["batch", *map(int, t.shape[1:])] for n, t in tensors}

    return {"name": stage.name, "onnx": target.name,
            "inputs": shapes(stage.inputs.items()),
            "outputs": shapes(zip(stage.outputs, results, strict=True)),
            **stage.description}  # fmt: skip


def export_post_stages(algorithm: Algorithm, folder: Path) -> list[dict[str, Any]]:
    """The algorithm's steps after its exported module, each written beside it (none when
    it has no :class:`PostStaged` capability)."""
    if not isinstance(algorithm, PostStaged):
        return []
    return [export_stage(stage, folder) for stage in algorithm.post_stages()]
