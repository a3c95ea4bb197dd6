"""Learning algorithms and the vectorised environment protocol they train on."""

from __future__ import annotations

from abc import abstractmethod
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, ClassVar, Protocol, runtime_checkable

from retarget.errors import PluginError
from retarget.kinds.base import ConfigT, Plugin
from retarget.kinds.comm import SINGLE, Comm
from retarget.kinds.iteration import IterationResult
from retarget.kinds.pose_estimator import PoseEstimator

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
    a plain dict of statistics is still accepted); ``act`` is the deterministic policy used
    by eval and export. ``state_dict`` must hold everything needed to resume exactly.
    """

    kind: ClassVar[str] = "algorithm"
    kinematic: ClassVar[bool] = False
    """True for a method that learns from the motion library instead of acting (a pose
    estimator): it needs a retarget environment (library, sensors), and the contract suite
    checks its :meth:`pose_estimator` instead of :meth:`act`."""
    distributed: ClassVar[bool] = False
    """True for an algorithm that trains data-parallel under torchrun: it uses :attr:`comm`
    to start every rank from the same weights, average gradients and merge statistics.
    ``retarget train`` refuses to start several ranks of an algorithm that does not."""
    comm: Comm = SINGLE
    """The ranks of this run (:mod:`retarget.train.distributed`), set before :meth:`setup`;
    one process without torchrun."""

    @abstractmethod
    def setup(self, env: VecEnv, generator: torch.Generator | None = None) -> None: ...

    @abstractmethod
    def train_iteration(self, env: VecEnv) -> IterationResult | dict[str, float]: ...

    @abstractmethod
    def act(self, obs: Mapping[str, torch.Tensor]) -> torch.Tensor: ...

    @abstractmethod
    def state_dict(self) -> dict[str, Any]: ...

    @abstractmethod
    def load_state_dict(self, state: Mapping[str, Any]) -> None: ...

    def fresh_rank(self, generator: torch.Generator) -> None:
        """This rank resumes a distributed run whose checkpoint holds no state for it (the
        run is resumed with more ranks than it was saved with): the shared weights, optimiser
        and statistics were loaded from rank 0's state; forget what belonged to rank 0's
        environments (its last observation, episode counters) and draw this rank's own
        randomness from ``generator``. Only algorithms with :attr:`distributed` need it."""

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

    def warm_start(self, state: Mapping[str, Any], inputs: Mapping[str, torch.Tensor]) -> None:
        """Start from the learned weights of another run's checkpoint (``state``, what its
        ``state_dict`` returned) instead of from scratch: fine-tuning a flat-ground walker in a
        scene, or a curriculum that changes the recipe between stages.

        ``inputs`` maps each observation group to a ``(D_new,)`` long tensor: the column of the
        old group that feeds each new column, or -1 for an input the old run did not have (a
        new observer). Nothing else of the old run is taken over (optimiser, counters). An
        algorithm that cannot do this keeps this default, which says so.
        """
        raise PluginError(
            "cannot start from another run's weights", plugin=self.name,
            hint="train from scratch (drop --init-from)",
        )

    def pose_estimator(self) -> PoseEstimator | None:
        """For a kinematic method (a pose estimator, which outputs a body instead of actions):
        the object ``retarget eval`` measures (a
        :class:`~retarget.kinds.pose_estimator.PoseEstimator`). ``None`` (the default): a
        policy, evaluated by stepping physics with :meth:`act`."""
        return None

    def export_metadata(self, env: Any) -> dict[str, Any] | None:
        """The JSON sidecar of an exported model whose input or output is not a policy's
        (observation group in, actions out); ``None`` (the default): the policy sidecar."""
        return None

    def policy(self) -> tuple[str, torch.nn.Module]:
        """The deployable policy: ``(group, module)`` where ``module`` maps that observation
        group's raw ``(B, D)`` float32 tensor to actions ``(B, A)`` in [-1, 1], normalisation
        included. ``retarget export`` turns it into ONNX; an algorithm that cannot be exported
        keeps this default."""
        raise NotImplementedError(f"algorithm '{self.name}' does not provide an exportable policy")
