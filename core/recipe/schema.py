"""JSON Schema of recipes for editor completion, built from the plugins installed right now.

Each component slot becomes a ``oneOf`` over the registered plugins of its kind, each branch
being that plugin's ``Config`` schema plus a constant ``type``.
"""

from __future__ import annotations

import copy
from typing import Any

from retarget.kinds.lookup import PluginLookup
from retarget.recipe.model import SLOTS, Recipe


def _plugin_branch(kind: str, name: str, config_schema: dict[str, Any]) -> dict[str, Any]:
    schema = copy.deepcopy(config_schema)
    defs = schema.pop("$defs", {})
    props = {"type": {"const": name}, **schema.get("properties", {})}
    branch: dict[str, Any] = {
        "title": f"{kind} {name}",
        "type": "object",
        "properties": props,
        "required": ["type", *schema.get("required", [])],
        "additionalProperties": False,
    }
    if defs:
        branch["$defs"] = defs
    return branch


def recipe_schema(registry: PluginLookup) -> dict[str, Any]:
    schema = Recipe.model_json_schema()
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    defs = schema.setdefault("$defs", {})
    kinds = set(SLOTS.values()) | {"motion_format"}
    for kind in sorted(kinds):
        branches = []
        for name in registry.names(kind):
            entry = registry.get(kind, name)
            branch = _plugin_branch(kind, name, entry.cls.Config.model_json_schema())
            branches.append(branch)
            branches.append({"const": name, "title": f"{kind} {name} (shorthand)"})
        defs[f"{kind}_component"] = {"oneOf": branches} if branches else {"type": "object"}
    props = schema["properties"]
    for slot, kind in SLOTS.items():
        ref = {"$ref": f"#/$defs/{kind}_component"}
        if slot in {"sensors", "observers", "callbacks"}:
            props[slot] = {"type": "array", "items": ref}
        elif slot in {"rewards", "terminations"}:
            props[slot] = {"type": "object", "additionalProperties": ref}
        elif slot == "character":
            props[slot] = ref
        else:
            props[slot] = {"anyOf": [ref, {"type": "null"}]}
    return schema
