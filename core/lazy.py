"""Package exports resolved on first use (PEP 562), so importing a package stays cheap.

``import retarget`` or ``from retarget.learn import PPOConfig`` must not pay for torch or
MuJoCo: the CLI starts, lists plugins and prints help without them. A package names what it
exports and from which module; the module is imported the first time a name is asked for.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from typing import Any


def lazy_exports(package: str, exports: Mapping[str, str]) -> Callable[[str], Any]:
    """A module ``__getattr__`` for ``package`` that imports ``exports[name]`` on first use."""
    namespace = importlib.import_module(package).__dict__

    def __getattr__(name: str) -> Any:
        module = exports.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(module), name)
        namespace[name] = value  # later lookups are plain attribute reads
        return value

    return __getattr__
