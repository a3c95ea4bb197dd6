"""Actor and critic networks: plain MLPs with a Gaussian action head.

Weights are initialised from an explicit ``torch.Generator`` (never the global RNG) so that a
seeded run builds bit-identical networks whatever else touched the global seed before it.
Orthogonal initialisation with a small gain on the policy output keeps the first actions
near zero torque, so early episodes are not dominated by random full-scale torques.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence

import torch
from torch import nn

from retarget.learn.columns import ImageInput
from retarget.learn.encoders import InputEncoder

ACTIVATIONS: dict[str, type[nn.Module]] = {
    "tanh": nn.Tanh,
    "elu": nn.ELU,
    "relu": nn.ReLU,
}


def mlp(sizes: Sequence[int], activation: str = "tanh") -> nn.Sequential:
    """Linear layers with ``activation`` between them and a linear output."""
    act = ACTIVATIONS[activation]
    layers: list[nn.Module] = []
    for i, (a, b) in enumerate(itertools.pairwise(sizes)):
        layers.append(nn.Linear(a, b))
        if i < len(sizes) - 2:
            layers.append(act())
    return nn.Sequential(*layers)


def init_mlp_(net: nn.Sequential, generator: torch.Generator | None, output_gain: float) -> None:
    """Orthogonal weights (gain sqrt(2) hidden, ``output_gain`` last), zero biases."""
    linears = [m for m in net if isinstance(m, nn.Linear)]
    with torch.no_grad():
        for i, layer in enumerate(linears):
            gain = output_gain if i == len(linears) - 1 else math.sqrt(2.0)
            nn.init.orthogonal_(layer.weight, gain=gain, generator=generator)
            layer.bias.zero_()


class GaussianActor(nn.Module):
    """Mean action from an MLP plus a state-independent standard deviation.

    ``learn_std=False`` keeps the exploration noise fixed, as the paper does: the std is then a
    buffer, saved with the model but never touched by the optimiser.
    """

    def __init__(
        self,
        obs_dim: int,
        action_dim: int,
        hidden: Sequence[int],
        *,
        activation: str = "tanh",
        init_std: float = 0.1,
        learn_std: bool = False,
        generator: torch.Generator | None = None,
        images: Sequence[ImageInput] = (),
    ) -> None:
        super().__init__()
        # image sources get a convolutional encoder; without any the actor is a plain MLP
        self.encoder = InputEncoder(obs_dim, images) if images else None
        inputs = self.encoder.out_dim if self.encoder is not None else obs_dim
        self.net = mlp([inputs, *hidden, action_dim], activation)
        init_mlp_(self.net, generator, output_gain=0.01)
        log_std = torch.full((action_dim,), math.log(init_std))
        if learn_std:
            self.log_std = nn.Parameter(log_std)
        else:
            self.register_buffer("log_std", log_std)

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        if self.encoder is not None:
            obs = self.encoder(obs)
        return self.net(obs)

    def std(self) -> torch.Tensor:
        return self.log_std.exp()

    def log_prob(self, mean: torch.Tensor, action: torch.Tensor) -> torch.Tensor:
        """Summed diagonal-Gaussian log density, written out (cheaper than
        ``torch.distributions`` for the many small calls of a rollout)."""
        z = (action - mean) / self.log_std.exp()
        return -(0.5 * z.square() + self.log_std + 0.5 * math.log(2 * math.pi)).sum(-1)

    def entropy(self) -> torch.Tensor:
        """Entropy of the (state-independent) Gaussian, a scalar."""
        return (self.log_std + 0.5 * math.log(2 * math.pi * math.e)).sum()


class Critic(nn.Module):
    """State value from the critic observation group (privileged, asymmetric)."""

    def __init__(
        self,
        obs_dim: int,
        hidden: Sequence[int],
        *,
        activation: str = "tanh",
        generator: torch.Generator | None = None,
        images: Sequence[ImageInput] = (),
    ) -> None:
        super().__init__()
        self.encoder = InputEncoder(obs_dim, images) if images else None
        inputs = self.encoder.out_dim if self.encoder is not None else obs_dim
        self.net = mlp([inputs, *hidden, 1], activation)
        init_mlp_(self.net, generator, output_gain=1.0)

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        if self.encoder is not None:
            obs = self.encoder(obs)
        return self.net(obs).squeeze(-1)
