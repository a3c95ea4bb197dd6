"""A network an application runs after an exported module, on its output and inputs of its own.

Some methods end in a step that is neither the network nor the application's business: a pose
estimator's reach puts the estimated wrists on the controllers along the user's own arm
(:mod:`retarget.learn.reach`), which needs the user's bone lengths, unknown when the network
was trained. ``retarget export --onnx`` writes each such step as an ONNX file of its own beside
the exported module, and the sidecar's ``after`` list says which inputs it takes and where each
comes from, so what an application runs is what ``retarget eval`` measured.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import torch


@dataclass(frozen=True)
class DeployStage:
    """One step after the exported module: ``module`` maps the tensors ``inputs`` names (in
    that order; examples with a batch of one or more, used to trace it) to ``outputs``."""

    name: str
    module: torch.nn.Module
    inputs: dict[str, torch.Tensor]
    outputs: tuple[str, ...]
    description: dict[str, Any] = field(default_factory=dict)
    """Sidecar entries: where each input comes from, what the outputs replace."""
