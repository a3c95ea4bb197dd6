"""What an algorithm can do beyond training: one protocol per capability.

:class:`~retarget.kinds.algorithm.Algorithm` is the core every algorithm has (set up on an
environment, train an iteration, save and restore its state). The rest is optional, and an
algorithm has a capability by defining its method:

* :class:`Acting`: ``act(obs)``, deterministic actions: ``retarget eval``, ``play`` and
  ``serve`` step physics with it.
* :class:`Exportable`: ``policy()``, the deployable module ``retarget export`` writes.
* :class:`PostStaged`: ``post_stages()``, networks an application runs after that module
  (:class:`~retarget.kinds.deploy_stage.DeployStage`), written beside it.
* :class:`PoseEstimating`: ``pose_estimator()``, a kinematic method (it outputs a body, not
  actions): evaluated by placing the character in its estimate; it learns from the motion
  library and needs a :class:`~retarget.kinds.tracking_env.TrackingEnv`.
* :class:`WarmStartable`: ``warm_start(state, inputs)``, ``retarget train --init-from``.
* :class:`DataParallel`: ``fresh_rank(generator)``, an algorithm that trains data-parallel
  under torchrun (it averages gradients and merges statistics over ``self.comm``).

Callers ask with ``isinstance(algorithm, Acting)`` (or :func:`require`, which names the
algorithm and what it lacks), so no flag can disagree with what the class does.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, Protocol, TypeVar, runtime_checkable

from retarget.errors import PluginError

if TYPE_CHECKING:
    import torch

    from retarget.kinds.deploy_stage import DeployStage
    from retarget.kinds.pose_estimator import PoseEstimator


@runtime_checkable
class Acting(Protocol):
    def act(self, obs: Mapping[str, torch.Tensor]) -> torch.Tensor:
        """Deterministic actions ``(N, A)`` in [-1, 1] for observation groups ``obs``."""
        ...


@runtime_checkable
class Exportable(Protocol):
    def policy(self) -> tuple[str, torch.nn.Module]:
        """``(group, module)``: ``module`` maps that group's raw ``(B, D)`` float32 tensor to
        the exported output (actions in [-1, 1] for a policy), normalisation included."""
        ...


@runtime_checkable
class PostStaged(Protocol):
    def post_stages(self) -> list[DeployStage]:
        """Steps an application runs on the exported module's output (none: an empty list),
        each exported as its own ONNX file."""
        ...


@runtime_checkable
class PoseEstimating(Protocol):
    def pose_estimator(self) -> PoseEstimator:
        """What ``retarget eval`` measures (a
        :class:`~retarget.kinds.pose_estimator.PoseEstimator`)."""
        ...


@runtime_checkable
class WarmStartable(Protocol):
    def warm_start(self, state: Mapping[str, Any], inputs: Mapping[str, torch.Tensor]) -> None:
        """Start from another run's learned weights (``state``); ``inputs`` maps each new
        input column of each group to the old column that feeds it, or -1."""
        ...


@runtime_checkable
class DataParallel(Protocol):
    def fresh_rank(self, generator: torch.Generator) -> None:
        """This rank resumes a run whose checkpoint holds no state for it: forget rank 0's
        per-environment state and draw this rank's randomness from ``generator``."""
        ...


CAPABILITIES: dict[str, type] = {
    "acting": Acting,
    "exportable": Exportable,
    "post_staged": PostStaged,
    "pose_estimating": PoseEstimating,
    "warm_startable": WarmStartable,
    "data_parallel": DataParallel,
}
"""Every capability by the name ``retarget plugins show`` and errors use."""

C = TypeVar("C")


def capabilities(algorithm: object) -> list[str]:
    """The names of the capabilities an algorithm (instance or class) has."""
    if isinstance(algorithm, type):
        return [n for n, p in CAPABILITIES.items() if issubclass(algorithm, p)]
    return [n for n, p in CAPABILITIES.items() if isinstance(algorithm, p)]


_LACKS = {
    "acting": "drives no character (it has no act())",
    "exportable": "has no exportable policy (no policy())",
    "post_staged": "has no steps after its exported module (no post_stages())",
    "pose_estimating": "is not a pose estimator (no pose_estimator())",
    "warm_startable": "cannot start from another run's weights (no warm_start())",
    "data_parallel": "does not train data-parallel (no fresh_rank())",
}


def require(algorithm: object, capability: type[C], hint: str | None = None) -> C:
    """``algorithm`` as having ``capability``, or a :class:`PluginError` naming both."""
    if isinstance(algorithm, capability):
        return algorithm
    name = getattr(algorithm, "name", type(algorithm).__name__)
    what = next((n for n, p in CAPABILITIES.items() if p is capability), capability.__name__)
    raise PluginError(_LACKS.get(what, f"lacks {what}"), plugin=f"algorithm {name}", hint=hint)
