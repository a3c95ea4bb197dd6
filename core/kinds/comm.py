"""The ranks of a run as an algorithm sees them: :class:`Comm` and the one-process
:data:`SINGLE`. It lives in the plugin contract because an :class:`~retarget.Algorithm`
receives one; starting and ending the process group (torchrun) is
:mod:`retarget.train.distributed`'s job.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import torch
    from torch import nn


@dataclass(frozen=True)
class Comm:
    """This process's place among the ranks of a run, and the collectives learners use."""

    rank: int = 0
    size: int = 1
    local_size: int = 1
    """Ranks on this machine (they share its cores)."""

    @property
    def main(self) -> bool:
        """Whether this rank writes the run directory and prints progress."""
        return self.rank == 0

    @property
    def distributed(self) -> bool:
        return self.size > 1

    # ------------------------------------------------------------------ weights

    def broadcast_modules(self, modules: Iterable[nn.Module]) -> None:
        """Give every rank rank 0's parameters and buffers (networks are built from each
        rank's own seed, so they start different)."""
        if not self.distributed:
            return
        import torch
        import torch.distributed as dist

        for module in modules:
            for tensor in (*module.parameters(), *module.buffers()):
                with torch.no_grad():
                    dist.broadcast(tensor.data, src=0)

    def average_gradients(self, params: Sequence[nn.Parameter]) -> None:
        """Replace each gradient by its mean over the ranks: one flat all-reduce, so the
        cost is one message per optimiser step whatever the network's layer count. Every
        rank gets the same bits, so identical weights stay identical after the step."""
        if not self.distributed:
            return
        import torch
        import torch.distributed as dist

        grads = [p.grad if p.grad is not None else torch.zeros_like(p) for p in params]
        flat = torch.cat([g.reshape(-1) for g in grads])
        dist.all_reduce(flat)
        flat /= self.size
        offset = 0
        for p, g in zip(params, grads, strict=True):
            n = g.numel()
            chunk = flat[offset : offset + n].view_as(g)
            if p.grad is None:
                p.grad = chunk.clone()
            else:
                p.grad.copy_(chunk)
            offset += n

    # ------------------------------------------------------------------ statistics

    def all_stats(
        self, count: torch.Tensor, mean: torch.Tensor, var: torch.Tensor
    ) -> list[tuple[torch.Tensor, torch.Tensor, torch.Tensor]]:
        """Every rank's ``(count, mean, var)`` of a batch of samples, in rank order (this
        rank's alone without torchrun): a normaliser merges them one after another, so all
        ranks arrive at the same statistics."""
        if not self.distributed:
            return [(count, mean, var)]
        import torch
        import torch.distributed as dist

        packed = torch.cat([count.reshape(1).double(), mean.double(), var.double()])
        out = [torch.empty_like(packed) for _ in range(self.size)]
        dist.all_gather(out, packed)
        d = mean.numel()
        return [(p[0], p[1 : 1 + d].view_as(mean), p[1 + d :].view_as(var)) for p in out]

    def total(self, value: float) -> float:
        """The sum of ``value`` over the ranks (environment steps taken this iteration)."""
        if not self.distributed:
            return value
        import torch
        import torch.distributed as dist

        t = torch.tensor([float(value)], dtype=torch.float64)
        dist.all_reduce(t)
        return float(t.item())

    def any(self, flag: bool) -> bool:
        """True on every rank when it is true on one (a stop requested, a budget spent)."""
        if not self.distributed:
            return flag
        import torch
        import torch.distributed as dist

        t = torch.tensor([1.0 if flag else 0.0])
        dist.all_reduce(t, op=dist.ReduceOp.MAX)
        return bool(t.item() > 0)

    # ------------------------------------------------------------------ objects

    def gather(self, obj: Any) -> list[Any] | None:
        """Every rank's ``obj`` on rank 0 (in rank order), ``None`` elsewhere. Objects travel
        pickled between the run's own processes, never through a file."""
        if not self.distributed:
            return [obj]
        import torch.distributed as dist

        out: list[Any] | None = [None] * self.size if self.main else None
        dist.gather_object(obj, out, dst=0)
        return out

    def broadcast(self, obj: Any) -> Any:
        """Rank 0's ``obj`` on every rank (the run directory rank 0 created)."""
        if not self.distributed:
            return obj
        import torch.distributed as dist

        box = [obj if self.main else None]
        dist.broadcast_object_list(box, src=0)
        return box[0]

    def barrier(self) -> None:
        if self.distributed:
            import torch.distributed as dist

            dist.barrier()


SINGLE = Comm()
"""The communicator of a process started without torchrun."""
