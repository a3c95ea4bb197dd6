"""A run's last checkpoints averaged into one policy (``retarget average``).

Fine-tuning a policy by DAgger or PPO moves its weights by noisy steps, and a single
checkpoint is one draw of that noise: measured on motions it never saw, the headset-only
student's checkpoints fifty iterations apart lose 0 to 5 of 24 held-out walks. The mean of the
weights over the run's tail (Polyak averaging, stochastic weight averaging) sits in the middle
of the region those steps wander over and behaves like the run's trend rather than one draw
(the same student: 24 of 24 from the last 20 checkpoints of two stretches of its run).

Every floating-point tensor of the policy (what :func:`retarget.train.package_model.policy_only`
keeps: the actor, its observation statistics, a critic-free state) is averaged; integers
(counters) come from the newest checkpoint. The checkpoints must come from one run, so every
tensor has one shape; anything else is an error naming the file.
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import torch

from retarget.errors import RetargetError
from retarget.train.checkpoint import load_checkpoint, save_checkpoint
from retarget.train.package_model import policy_only
from retarget.train.run_dir import (
    CHECKPOINTS,
    LOCK,
    checkpoint_iteration,
    resolve_run,
    run_checkpoints,
)

AVERAGED_FROM = "averaged_from.json"
"""In the new run's directory: the run and checkpoint files its weights are the mean of."""
KEEP = ("train_settings.json", "metrics.csv", "init_from.txt")
"""Files of the source run copied beside the lock (a card's samples and CPU-hours read them)."""


def combine(base: Any, value: Any, fn: Callable[[torch.Tensor, torch.Tensor], torch.Tensor], *,
            file: Path, where: str, against: str, hint: str, keep: tuple[str, ...] = ()) -> Any:
    """``value``'s tree with each floating tensor ``fn(base's, value's)``; other leaves, and
    entries named in ``keep``, are ``value``'s. Two checkpoints of one network have the same
    entries and shapes: anything else is an error naming the entry, ``file`` and ``against``
    (what ``base`` is), so averaged or blended weights never mix different networks."""
    if isinstance(base, Mapping):
        if not isinstance(value, Mapping) or value.keys() != base.keys():
            raise RetargetError(f"'{where}' holds other entries {against}", file=str(file),
                                hint=hint)  # fmt: skip
        return type(value)(
            (k, value[k] if k in keep else combine(base[k], value[k], fn, file=file,
                                                   where=f"{where}.{k}", against=against,
                                                   hint=hint, keep=keep))
            for k in value
        )  # fmt: skip
    if isinstance(base, torch.Tensor) and base.is_floating_point():
        if not isinstance(value, torch.Tensor) or value.shape != base.shape:
            raise RetargetError(f"'{where}' has another shape {against}", file=str(file),
                                hint=hint)  # fmt: skip
        return fn(base, value)
    return value


def _floats(tree: Any, fn: Callable[[torch.Tensor, torch.Tensor], torch.Tensor],
            like: Any) -> Any:  # fmt: skip
    """``tree`` with ``fn(tensor, like's tensor)`` applied to its floating tensors."""
    if isinstance(tree, dict):
        return type(tree)((k, _floats(v, fn, like[k])) for k, v in tree.items())
    if isinstance(tree, torch.Tensor) and tree.is_floating_point():
        return fn(tree, like)
    return tree


def average_state(files: Sequence[Path]) -> dict[str, Any]:
    """The policy-only state whose floating tensors are the means over ``files``, read one at
    a time (memory of two checkpoints, however many are averaged)."""
    if not files:
        raise RetargetError("no checkpoints to average")
    total: Any = None
    newest: dict[str, Any] = {}
    for file in files:
        newest = policy_only(load_checkpoint(file))
        algorithm = newest["algorithm"]
        if total is None:
            total = _floats(algorithm, lambda t, _: t.double(), algorithm)
        else:
            total = combine(total, algorithm, lambda t, v: t + v.double(), file=file,
                            where="algorithm", against="than in the checkpoints before",
                            hint="average checkpoints of one run")  # fmt: skip
    mean = _floats(total, lambda t, like: (t / len(files)).to(like.dtype), newest["algorithm"])
    return {"algorithm": mean,
            "progress": newest.get("progress", {})}  # fmt: skip


def average_run(
    run: str | Path, out: str | Path, last: int, upto: int | None = None
) -> Path:
    """Write a run directory at ``out`` whose one checkpoint (named as the newest averaged)
    is the mean of ``run``'s ``last`` newest checkpoints, or of the ``last`` up to iteration
    ``upto`` (a checkpoint chosen earlier in a run that went on past it); returns ``out``."""
    source = resolve_run(run)
    if last < 1:
        raise RetargetError(f"--last must be at least 1, got {last}")
    files = run_checkpoints(source)
    if upto is not None:
        files = [f for f in files if checkpoint_iteration(f) <= upto]
        if not files or checkpoint_iteration(files[-1]) != upto:
            raise RetargetError(f"the run has no checkpoint of iteration {upto}",
                                file=str(source / CHECKPOINTS))  # fmt: skip
    files = files[-last:]
    if len(files) < last:
        within = f" up to iteration {upto}" if upto is not None else ""
        raise RetargetError(f"the run has {len(files)} checkpoints{within}, fewer than --last "
                            f"{last}", file=str(source / CHECKPOINTS))  # fmt: skip
    target = Path(out)
    if target.exists() and any(target.iterdir()):
        raise RetargetError("the output directory exists and is not empty", file=str(target),
                            hint="give a new --out")  # fmt: skip
    state = average_state(files)
    (target / CHECKPOINTS).mkdir(parents=True, exist_ok=True)
    shutil.copy2(source / LOCK, target / LOCK)
    for name in KEEP:
        if (source / name).is_file():
            shutil.copy2(source / name, target / name)
    save_checkpoint(target / CHECKPOINTS / files[-1].name, state)
    record = {"run": str(source), "checkpoints": [f.name for f in files]}
    (target / AVERAGED_FROM).write_text(json.dumps(record, indent=2) + "\n", encoding="utf-8")
    return target
