"""Turning a trained run into a shipped model: lock, policy-only checkpoint, model card.

The lock keeps the run's recipe with its motion path removed (the training data is not
shipped; the card names it) and a distilled student's teacher named as a shipped model, so
the directory works from any checkout. The checkpoint keeps what acting needs: the actor, its
observation statistics (``--init-from`` fine-tunes with a fresh critic, as from any run).
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

import yaml

from retarget.pretrained import CARD, MODELS, ModelCard
from retarget.train.checkpoint import load_checkpoint, save_checkpoint
from retarget.train.run_dir import CHECKPOINTS, CURRENT, LOCK, latest_checkpoint, resolve_run

TRAINING_ONLY = ("optimizer", "critic", "value_norm", "generator", "last_obs", "buffer",
                 "overlap", "episode_return", "episode_length", "finished_returns",
                 "finished_lengths")  # fmt: skip
"""Algorithm state only training reads (the learners load a checkpoint without it as
policy-only: acting, evaluating, exporting, distilling from it, warm starts)."""


def policy_only(state: dict[str, Any]) -> dict[str, Any]:
    """A checkpoint with only what acting (and fine-tuning) reads."""
    algorithm = {k: v for k, v in state["algorithm"].items() if k not in TRAINING_ONLY}
    return {"algorithm": algorithm, "progress": state.get("progress", {})}


def package(run: str | Path, card: ModelCard, *, teacher: str | None = None,
            models: Path = MODELS) -> Path:  # fmt: skip
    """Write ``models/NAME`` from ``run``'s newest checkpoint; returns the folder."""
    source = resolve_run(run)
    out = models / card.name
    if out.exists():
        shutil.rmtree(out)
    (out / CHECKPOINTS).mkdir(parents=True)
    lock = yaml.safe_load((source / LOCK).read_text(encoding="utf-8"))
    lock.setdefault("motions", {})["path"] = None
    lock["name"] = card.name
    if teacher is not None and isinstance(lock.get("algorithm"), dict):
        lock["algorithm"]["teacher"] = teacher
    (out / LOCK).write_text(yaml.safe_dump(lock, sort_keys=False), encoding="utf-8")
    ckpt = latest_checkpoint(source)
    save_checkpoint(out / CHECKPOINTS / ckpt.name, policy_only(load_checkpoint(ckpt)))
    # the model's own checkpoint by name: files kept beside it may carry higher numbers
    (out / CHECKPOINTS / CURRENT).write_text(ckpt.name + "\n", encoding="utf-8")
    (out / CARD).write_text(card.model_dump_json(indent=2) + "\n", encoding="utf-8")
    (out / "MODEL_CARD.md").write_text(render(card), encoding="utf-8")
    return out


def render(card: ModelCard) -> str:
    """The card as Markdown, for people browsing the package."""
    lines = [
        f"# {card.name}", "", card.summary, "",
        f"- character: {card.character}; sensors: {', '.join(card.sensors)}; "
        f"algorithm: {card.algorithm}" + (f" (teacher: {card.teacher})" if card.teacher else ""),
        f"- data: {card.data}",
        f"- samples: {card.env_steps:,} environment steps; {card.cpu_hours:.2f} CPU-hours",
        f"- licence of the training data: {card.licence}", "",
    ]  # fmt: skip
    for held_out, figures in card.metrics.items():
        lines += [f"## {held_out}", "", "| figure | value |", "|---|---:|"]
        lines += [f"| {k} | {'-' if v is None else format(v, '.3g')} |" for k, v in figures.items()]
        lines.append("")
    if card.notes:
        lines += ["## Notes", "", card.notes, ""]
    return "\n".join(lines)


def read_card(path: Path) -> ModelCard:
    return ModelCard.model_validate(json.loads(path.read_text(encoding="utf-8")))
