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
import re
import shutil
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import torch

from retarget.errors import RetargetError
from retarget.train.checkpoint import load_checkpoint, save_checkpoint
from retarget.train.package_model import policy_only
from retarget.train.run_dir import CHECKPOINTS, LOCK, resolve_run

AVERAGED_FROM = "averaged_from.json"
"""In the new run's directory: the run and checkpoint files its weights are the mean of."""
KEEP = ("train_settings.json", "metrics.csv", "init_from.txt")
"""Files of the source run copied beside the lock (a card's samples and CPU-hours read them)."""


def run_checkpoints(run: Path) -> list[Path]:
    """The run's numbered checkpoint files, oldest first."""
    numbered = []
    for file in (run / CHECKPOINTS).glob("ckpt-*.pt"):
        if found := re.fullmatch(r"ckpt-(\d+)\.pt", file.name):
            numbered.append((int(found.group(1)), file))
    return [file for _, file in sorted(numbered)]


def _mean(values: Sequence[Any], files: Sequence[Path], where: str) -> Any:
    first = values[-1]
    if isinstance(first, dict):
        for v, f in zip(values, files, strict=True):
            if not isinstance(v, dict) or v.keys() != first.keys():
                raise RetargetError(f"'{where}' holds other entries than in {files[-1].name}",
                                    file=str(f), hint="average checkpoints of one run")  # fmt: skip
        return type(first)((k, _mean([v[k] for v in values], files, f"{where}.{k}"))
                           for k in first)  # fmt: skip
    if isinstance(first, torch.Tensor) and first.is_floating_point():
        for v, f in zip(values, files, strict=True):
            if not isinstance(v, torch.Tensor) or v.shape != first.shape:
                raise RetargetError(f"'{where}' has another shape than in {files[-1].name}",
                                    file=str(f), hint="average checkpoints of one run")  # fmt: skip
        return torch.stack([v.double() for v in values]).mean(0).to(first.dtype)
    return first


def average_state(files: Sequence[Path]) -> dict[str, Any]:
    """The policy-only state whose floating tensors are the means over ``files``."""
    if not files:
        raise RetargetError("no checkpoints to average")
    states = [policy_only(load_checkpoint(f)) for f in files]
    return {"algorithm": _mean([s["algorithm"] for s in states], files, "algorithm"),
            "progress": states[-1].get("progress", {})}  # fmt: skip


def average_run(run: str | Path, out: str | Path, last: int) -> Path:
    """Write a run directory at ``out`` whose one checkpoint (named as the newest of ``run``)
    is the mean of ``run``'s ``last`` newest checkpoints; returns ``out``."""
    source = resolve_run(run)
    if last < 1:
        raise RetargetError(f"--last must be at least 1, got {last}")
    files = run_checkpoints(source)[-last:]
    if len(files) < last:
        raise RetargetError(f"the run has {len(files)} checkpoints, fewer than --last {last}",
                            file=str(source / CHECKPOINTS))  # fmt: skip
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
