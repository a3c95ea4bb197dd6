"""Convolutional encoders for image observations, chosen by the observation's shape.

A group's columns are flat; an image source (a sensor whose spec is ``(C, H, W)``) is cut out,
each of its ``C`` views goes through one small CNN (weights shared across the views, so a
four-camera rig does not need four times the samples), and the features replace the pixels
before the policy MLP. GroupNorm rather than BatchNorm, as SimXR's ablation prefers (and it
behaves the same for a batch of one at deployment). Any image sensor reuses this.
"""

from __future__ import annotations

from collections.abc import Sequence

import torch
from torch import nn

from retarget.learn.columns import ImageInput

FEATURES = 32
"""Features per view."""


def view_cnn(height: int, width: int, features: int = FEATURES) -> nn.Sequential:
    """``(B, 1, H, W)`` -> ``(B, features)``: two strided convolutions with GroupNorm, then a
    linear layer over the feature map (sized here, so the exported graph has fixed shapes)."""
    convs = nn.Sequential(
        nn.Conv2d(1, 16, 5, stride=2, padding=2), nn.GroupNorm(4, 16), nn.ReLU(),
        nn.Conv2d(16, 32, 3, stride=2, padding=1), nn.GroupNorm(8, 32), nn.ReLU(),
    )  # fmt: skip
    with torch.no_grad():
        cells = convs(torch.zeros(1, 1, height, width)).numel()
    return nn.Sequential(*convs, nn.Flatten(), nn.Linear(cells, features), nn.ReLU())


class InputEncoder(nn.Module):
    """Flat observation ``(B, D)`` -> ``(B, D')``: image columns replaced by CNN features."""

    def __init__(self, obs_dim: int, images: Sequence[ImageInput]) -> None:
        super().__init__()
        self.images = tuple(sorted(images, key=lambda i: i.start))
        keep = torch.ones(obs_dim, dtype=torch.bool)
        for image in self.images:
            keep[image.start : image.start + image.size] = False
        self.register_buffer("keep", keep.nonzero().flatten(), persistent=False)
        self.cnns = nn.ModuleList(view_cnn(i.shape[1], i.shape[2]) for i in self.images)
        self.out_dim = int(keep.sum()) + sum(FEATURES * i.shape[0] for i in self.images)

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        parts = [obs.index_select(-1, self.keep)]
        batch = obs.shape[:-1]
        for image, cnn in zip(self.images, self.cnns, strict=True):
            c, h, w = image.shape
            pixels = obs[..., image.start : image.start + image.size].reshape(-1, 1, h, w)
            parts.append(cnn(pixels).reshape(*batch, c * FEATURES))
        return torch.cat(parts, dim=-1)
