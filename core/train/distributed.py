"""Data-parallel training over ``torch.distributed``: what each rank shares with the others.

``torchrun --nproc-per-node K -m retarget train RECIPE`` starts K processes; each steps its own
batch of environments with its own seed, and the learners keep one set of weights by
averaging gradients before every optimiser step. The learners keep their tensors on the CPU
(the physics hands them CPU arrays), so the collectives run over gloo; ``RETARGET_DIST_BACKEND``
names another torch.distributed backend for learners that move their tensors to a GPU (nccl).
Running observation and return statistics are merged from every rank's samples, in
rank order, so every rank normalises with identical numbers. Rank 0 alone writes the run
directory (logs, checkpoints, the lock file).

A single process gets :data:`SINGLE`, whose every operation is the identity, so an algorithm
written against :class:`Comm` runs unchanged without torchrun.
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    pass


from retarget.kinds.comm import SINGLE, Comm

__all__ = ["SINGLE", "Comm", "from_environment", "shutdown"]



def from_environment() -> Comm:
    """The communicator torchrun describes in this process's environment (``RANK``,
    ``WORLD_SIZE``, ``LOCAL_WORLD_SIZE``, ``MASTER_ADDR``/``MASTER_PORT``), with the process
    group initialised; :data:`SINGLE` when the variables are absent or describe one rank."""
    size = int(os.environ.get("WORLD_SIZE", "1"))
    if size <= 1:
        return SINGLE
    import torch.distributed as dist

    if not dist.is_initialized():
        dist.init_process_group(backend=os.environ.get("RETARGET_DIST_BACKEND", "gloo"))
    return Comm(
        rank=dist.get_rank(),
        size=dist.get_world_size(),
        local_size=int(os.environ.get("LOCAL_WORLD_SIZE", str(size))),
    )


def shutdown() -> None:
    """Leave the process group (at the end of a distributed run)."""
    import torch.distributed as dist

    if dist.is_available() and dist.is_initialized():
        dist.destroy_process_group()
