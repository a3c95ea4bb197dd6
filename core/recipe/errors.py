"""Turning pydantic validation errors into one readable :class:`RecipeError`."""

from __future__ import annotations

import difflib
from collections.abc import Iterable

from pydantic import BaseModel, ValidationError

from retarget.errors import RecipeError
from retarget.recipe.source import RecipeSource


def dotted(loc: Iterable[object]) -> str:
    return ".".join(str(part) for part in loc)


def from_validation(
    exc: ValidationError,
    source: RecipeSource,
    *,
    prefix: str = "",
    plugin: str | None = None,
    model: type[BaseModel] | None = None,
) -> RecipeError:
    """The first error of ``exc`` as a RecipeError naming file, line, field and plugin.

    An unknown field gets a "did you mean" from ``model``'s field names; further errors are
    counted so the user knows there is more to fix.
    """
    errors = exc.errors()
    first = errors[0]
    loc = [p for p in first["loc"] if not (isinstance(p, str) and p.startswith("function-"))]
    field = ".".join(filter(None, [prefix, dotted(loc)]))
    file, line = source.locate(field)
    kind = first["type"]
    hint = None
    if kind == "extra_forbidden":
        message = "unknown field"
        if model is not None and loc:
            known = list(_fields_at(model, loc[:-1]))
            close = difflib.get_close_matches(str(loc[-1]), known, n=3, cutoff=0.5)
            hint = (f"did you mean {' or '.join(repr(c) for c in close)}? " if close else "") + (
                f"valid fields: {', '.join(known)}" if known else ""
            )
    elif kind == "missing":
        message = "required field is missing"
    else:
        got = first.get("input")
        shown = repr(got) if not isinstance(got, dict | list) or len(repr(got)) < 60 else "..."
        message = f"{first['msg']} (got {shown})"
    if len(errors) > 1:
        message += f" [and {len(errors) - 1} more error(s)]"
    return RecipeError(message, file=file, line=line, field=field, plugin=plugin, hint=hint)


def _fields_at(model: type[BaseModel], loc: list[object]) -> Iterable[str]:
    """Field names of the (possibly nested) model reached by ``loc``; empty if unknown."""
    current: type[BaseModel] | None = model
    for part in loc:
        if current is None or not isinstance(part, str) or part not in current.model_fields:
            return []
        annotation = current.model_fields[part].annotation
        current = _model_in(annotation)
    return list(current.model_fields) if current is not None else []


def _model_in(annotation: object) -> type[BaseModel] | None:
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in getattr(annotation, "__args__", ()) or ():
        found = _model_in(arg)
        if found is not None:
            return found
    return None
