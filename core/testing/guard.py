"""A behavioural guard against per-environment Python loops in batched plugin code.

Inside :class:`NoPerEnvLoops`, tensor operations that only make sense when code iterates over
environments (``.item()``, ``.tolist()``, iterating or unbinding a tensor, truth-testing a
tensor, ``.numpy()``, and integer indexing of a tensor whose leading dimension is the batch)
raise :class:`VectorisationError`. It checks what the code does, not how long it takes.
"""

from __future__ import annotations

import torch
from torch.overrides import TorchFunctionMode

_BANNED = {
    torch.Tensor.item: "Tensor.item()",
    torch.Tensor.tolist: "Tensor.tolist()",
    torch.Tensor.__iter__: "iterating over a tensor",
    torch.Tensor.unbind: "Tensor.unbind()",
    torch.unbind: "torch.unbind()",
    torch.Tensor.__bool__: "truth-testing a tensor (if/while on tensor values)",
    torch.Tensor.__int__: "int(tensor)",
    torch.Tensor.__float__: "float(tensor)",
    torch.Tensor.__index__: "using a tensor as a Python index",
    torch.Tensor.numpy: "Tensor.numpy()",
}


class VectorisationError(AssertionError):
    """Batched plugin code did something per environment."""


class NoPerEnvLoops(TorchFunctionMode):
    """Raise on per-environment tensor access while active; ``batch`` is the env count N."""

    def __init__(self, batch: int) -> None:
        super().__init__()
        self.batch = batch

    def __torch_function__(self, func, types, args=(), kwargs=None):
        kwargs = kwargs or {}
        what = _BANNED.get(func)
        if what is not None:
            raise VectorisationError(f"{what} inside batched code: vectorise over environments")
        if func in (torch.Tensor.__getitem__, torch.Tensor.__setitem__) and args:
            tensor, index = args[0], args[1]
            lead = index[0] if isinstance(index, tuple) and index else index
            if (
                isinstance(tensor, torch.Tensor)
                and tensor.ndim > 0
                and tensor.shape[0] == self.batch
                and isinstance(lead, int)
                and not isinstance(lead, bool)
            ):
                raise VectorisationError(
                    f"integer index [{lead}] into a tensor whose leading dimension is the "
                    f"{self.batch} environments: index all environments at once"
                )
        return func(*args, **kwargs)
