"""Learning algorithms and the vectorised environment protocol they train on."""

from __future__ import annotations

from abc import abstractmethod
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, ClassVar, Protocol, runtime_checkable

from retarget.kinds.base import ConfigT, Plugin
from retarget.kinds.comm import SINGLE, Comm
from retarget.kinds.iteration import IterationResult

if TYPE_CHECKING:
    import torch

    from retarget.kinds.lookup import PluginLookup


@runtime_checkable
class VecEnv(Protocol):
    """What an algorithm trains on: N environments stepped together.

    Observations are a mapping of group name (``actor``, ``critic``, ...) to ``(N, D)``
    float32 tensors; ``step`` returns ``(obs, reward (N,), terminated (N,), truncated (N,),
    info)``. Environments that end are reset inside ``step``.
    """

    num_envs: int
    obs_dims: Mapping[str, int]
    action_dim: int

    def reset(self) -> Mapping[str, torch.Tensor]: ...

    def step(
        self, action: torch.Tensor
    ) -> tuple[Mapping[str, torch.Tensor], torch.Tensor, torch.Tensor, torch.Tensor, dict]: ...


class Algorithm(Plugin[ConfigT]):
    """Base class of learning algorithms (PPO, distillation, ...).

    ``setup`` builds networks for an environment; ``train_iteration`` collects one rollout and
    updates, returning an :class:`~retarget.kinds.iteration.IterationResult` (its statistics,
    the samples it learnt from when it stepped no environment, the progress bar's figures;
    a plain dict of statistics is still accepted). ``state_dict`` must hold everything
    needed to resume exactly. What an algorithm can do beyond that (act, export a policy,
    estimate poses, start from another run's weights, train data-parallel) it has by
    defining the method of that capability (:mod:`retarget.kinds.capabilities`).
    """

    kind: ClassVar[str] = "algorithm"
    learns_from_reward: ClassVar[bool] = True
    """Whether the environment's reward drives learning (reinforcement learning); a learner
    that imitates a teacher, an expert or poses sets False, and the trainer then does not
    judge the recipe's reward terms for it."""
    comm: Comm = SINGLE
    """The ranks of this run (:mod:`retarget.train.distributed`), set before :meth:`setup`;
    one process without torchrun."""

    @abstractmethod
    def setup(self, env: VecEnv, generator: torch.Generator | None = None) -> None: ...

    @abstractmethod
    def train_iteration(self, env: VecEnv) -> IterationResult | dict[str, float]: ...

    @abstractmethod
    def state_dict(self) -> dict[str, Any]: ...

    @abstractmethod
    def load_state_dict(self, state: Mapping[str, Any]) -> None: ...

    def prepare_recipe(self, recipe: dict[str, Any], registry: PluginLookup) -> dict[str, Any]:
        """Amend a new run's recipe before it is resolved and locked: ``recipe`` is the
        resolved recipe as a plain dict (``ResolvedRecipe.to_dict``); return it, changed or
        not. A distillation algorithm adds the sensors and the observation group its teacher
        reads here, so that the run's ``recipe.lock.yaml`` states exactly what ran and the
        run can be evaluated, resumed and exported without the teacher. Errors about the
        recipe (a teacher of another character) are raised here, before anything is built.
        The default changes nothing.
        """
        return recipe

    def connect(self, registry: PluginLookup) -> None:
        """Receive the invocation's plugin registry (``retarget.registry.Registry``) before
        :meth:`setup`, for an algorithm that loads other runs (a teacher). Default: unused."""

    def export_metadata(self, env: Any) -> dict[str, Any] | None:
        """The JSON sidecar of an exported model whose input or output is not a policy's
        (observation group in, actions out); ``None`` (the default): the policy sidecar."""
        return None
