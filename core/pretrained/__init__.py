"""Pretrained models shipped inside the package, so an avatar follows its user without hours
of training first.

Each model is a run directory under ``models/NAME/`` (its ``recipe.lock.yaml``, one
policy-only checkpoint, and ``card.json``, the model card: data, samples, CPU-hours, metrics on
held-out motion, licence). ``pretrained:NAME`` is accepted wherever a run directory is (eval,
play, export, serve, view, ``--teacher``, ``--init-from``); ``retarget pretrained`` lists them.
The checkpoints hold the actor and its observation statistics only (what acting needs), so
they are small and cannot be resumed; the full training state of each is kept outside the
package, in ``benchmarks/pretrain/``.
"""

from __future__ import annotations

import difflib
import json
from pathlib import Path

from pydantic import BaseModel, ConfigDict, Field

from retarget.errors import RetargetError

PREFIX = "pretrained:"
MODELS = Path(__file__).resolve().parent / "models"
CARD = "card.json"


class ModelCard(BaseModel):
    """What a shipped model is and how it was made (``card.json``)."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    name: str
    summary: str
    character: str
    sensors: list[str]
    algorithm: str
    data: str = Field(description="which motion trained it, and what was held out")
    licence: str = Field(description="terms of the training data the weights inherit")
    env_steps: int
    cpu_hours: float
    teacher: str | None = None
    metrics: dict[str, dict[str, float | None]] = Field(
        default_factory=dict, description="held-out set -> figure -> value (null: undefined, "
        "e.g. an error over successful runs when none succeeded)",
    )
    notes: str = ""


def names() -> list[str]:
    """The shipped models, sorted."""
    if not MODELS.is_dir():
        return []
    return sorted(p.name for p in MODELS.iterdir() if (p / CARD).is_file())


def card(name: str) -> ModelCard:
    path = model_dir(name) / CARD
    try:
        return ModelCard.model_validate(json.loads(path.read_text(encoding="utf-8")))
    except (OSError, ValueError) as exc:
        raise RetargetError(f"unreadable model card: {exc}", file=str(path)) from None


def model_dir(name: str) -> Path:
    """The run directory of pretrained model ``name`` (an error lists the known ones)."""
    known = names()
    if name not in known:
        close = difflib.get_close_matches(name, known, n=1)
        raise RetargetError(
            f"no pretrained model '{name}'",
            hint=(f"did you mean '{close[0]}'? " if close else "")
            + f"known: {', '.join(known) or '(none)'}; list them with `retarget pretrained`",
        )
    return MODELS / name


def is_pretrained(path: str | Path) -> bool:
    return str(path).startswith(PREFIX)


def resolve(path: str | Path) -> Path:
    """``pretrained:NAME`` as its directory; any other path unchanged."""
    text = str(path)
    return model_dir(text[len(PREFIX) :]) if text.startswith(PREFIX) else Path(path)


def inside_models(path: Path) -> bool:
    """Whether ``path`` is a shipped model's folder (outputs go elsewhere: the package may be
    read-only, and a shipped model is never changed by using it)."""
    try:
        path.resolve().relative_to(MODELS)
    except ValueError:
        return False
    return True
