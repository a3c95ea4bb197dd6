"""The plugin system: the hooks a plugin implements, loading entry points, and the registry.

One :class:`Registry` is built per invocation (``load_plugins``) and handed down to whatever
needs plugins, so a recipe, its motion format and its teacher resolve against the same set.
"""

from __future__ import annotations

from retarget.registry.store import Entry, Registry

__all__ = ["Entry", "Registry"]
