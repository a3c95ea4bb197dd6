"""Plugin loading: every entry point of the ``retarget`` group, each in isolation.

A plugin that fails to import, registers something invalid or raises inside its hook produces
one warning naming the plugin, its distribution and the error, and everything else keeps
working. Strict mode (``--strict-plugins`` / ``RETARGET_STRICT_PLUGINS=1``, and always in the
contract suite) turns those warnings into :class:`retarget.errors.PluginError`. Two plugins
that claim one name are both left out, with a warning naming both.
``RETARGET_LOAD_PLUGINS=dist-a,dist-b`` restricts which third-party distributions load
(retarget's own built-ins always load; an empty value loads none else).
"""

from __future__ import annotations

import os
import traceback
import warnings
from collections.abc import Iterable, Mapping
from importlib.metadata import EntryPoint, entry_points
from types import ModuleType

import pluggy

from retarget.errors import PluginError
from retarget.registry import hookspecs
from retarget.registry.store import DuplicateName, Entry, Registry

GROUP = "retarget"
OWN_DISTRIBUTION = "retarget"


class PluginLoadWarning(UserWarning):
    """A plugin could not be loaded; the rest of retarget keeps working."""


def strict_from_env() -> bool:
    return os.environ.get("RETARGET_STRICT_PLUGINS", "").strip().lower() in {"1", "true", "yes"}


def _allowlist() -> set[str] | None:
    raw = os.environ.get("RETARGET_LOAD_PLUGINS")
    if raw is None:
        return None
    return {part.strip() for part in raw.split(",") if part.strip()}


def _dist(ep: EntryPoint, seen: dict[int, tuple[str, str]]) -> tuple[str, str]:
    """Name and version of an entry point's distribution, read once per distribution (each
    read parses its METADATA file, and a distribution has many entry points)."""
    dist = getattr(ep, "dist", None)
    if dist is None:
        return "unknown", "?"
    if id(dist) not in seen:
        meta = dist.metadata
        seen[id(dist)] = (meta["Name"] or dist.name, meta["Version"] or "?")
    return seen[id(dist)]


def _entry_points() -> list[EntryPoint]:
    return sorted(entry_points(group=GROUP), key=lambda ep: ep.name)


def load_plugins(
    *,
    strict: bool | None = None,
    modules: Mapping[str, ModuleType | object] | None = None,
    use_entry_points: bool = True,
) -> Registry:
    """Load all plugins into a fresh :class:`Registry`.

    ``modules`` registers extra plugin objects under the given names (distribution ``local``):
    tests use it for test doubles, scripts for one-off plugins.
    """
    if strict is None:
        strict = strict_from_env()
    registry = Registry()
    pm = pluggy.PluginManager(hookspecs.PROJECT)
    pm.add_hookspecs(hookspecs)
    provenance: dict[str, tuple[str, str]] = {}

    def problem(plugin: str, dist: str, what: str, exc: BaseException) -> None:
        if isinstance(exc, PluginError):
            detail = exc.message + (f" ({exc.hint})" if exc.hint else "")
        else:
            detail = "".join(traceback.format_exception_only(type(exc), exc)).strip()
        message = f"plugin '{plugin}' from {dist} {what}: {detail}"
        if strict:
            raise PluginError(f"{what}: {detail}", plugin=f"{plugin} ({dist})") from exc
        registry.problems.append(message)
        warnings.warn(message, PluginLoadWarning, stacklevel=3)

    candidates: list[tuple[str, str, str, object]] = []
    if use_entry_points:
        allow = _allowlist()
        dists: dict[int, tuple[str, str]] = {}
        for ep in _entry_points():
            dist, version = _dist(ep, dists)
            if allow is not None and dist != OWN_DISTRIBUTION and dist not in allow:
                continue
            try:
                module = ep.load()
            except KeyboardInterrupt:
                raise
            except BaseException as exc:  # sys.exit() or worse at import is a broken plugin too
                problem(ep.name, dist, "failed to import", exc)
                continue
            candidates.append((ep.name, dist, version, module))
    for name, module in (modules or {}).items():
        candidates.append((name, "local", "0", module))

    clashing: set[str] = set()
    for name, dist, version, module in candidates:
        held = provenance.get(name, ("", ""))[0] if pm.has_plugin(name) else ""
        if OWN_DISTRIBUTION in (held, dist) and held != dist and held:
            # a built-in's entry point is never shadowed: the other one is left out, named
            intruder = dist if held == OWN_DISTRIBUTION else held
            problem(
                name, intruder, "shares its entry point name with a built-in of retarget; the "
                "built-in is kept and this one is not loaded",
                PluginError("rename this entry point"),
            )  # fmt: skip
            if held == OWN_DISTRIBUTION:
                continue
            pm.unregister(name=name)
        elif pm.has_plugin(name) or name in clashing:
            if pm.has_plugin(name):
                other = provenance[name][0]
                pm.unregister(name=name)
            else:
                other = "another distribution"
            clashing.add(name)
            problem(
                name, dist, f"shares its entry point name with {other}; neither is loaded",
                PluginError("rename one entry point, or uninstall one distribution"),
            )
            continue
        try:
            pm.register(module, name=name)
        except Exception as exc:
            problem(name, dist, "has invalid hook implementations", exc)
            continue
        provenance[name] = (dist, version)
    for _ in range(len(candidates) + 1):  # each round finds one plugin with an unknown hook
        try:
            pm.check_pending()
            break
        except pluggy.PluginValidationError as exc:
            plugin = getattr(exc, "plugin", None)
            pname = pm.get_name(plugin) if plugin is not None else "?"
            problem(
                pname or "?",
                provenance.get(pname or "", ("?", ""))[0],
                "implements an unknown hook",
                exc,
            )
            if plugin is None:
                break
            pm.unregister(plugin)

    for hook_name, kind in hookspecs.HOOK_KINDS.items():
        caller = getattr(pm.hook, hook_name)
        for impl in reversed(caller.get_hookimpls()):  # registration order
            dist, version = provenance.get(impl.plugin_name, ("?", "?"))
            _call_hook(impl, kind, dist, version, registry, problem)
    return registry


def _call_hook(impl, kind, dist, version, registry, problem) -> None:
    """Call one plugin's register hook; what it registers lands only if the hook succeeds."""
    staged: list[Entry] = []

    def register(cls, *, name: str | None = None, aliases: Iterable[str] = ()) -> None:
        label = name if name is not None else getattr(cls, "name", None)
        if not isinstance(label, str):
            raise PluginError(f"{cls!r} has no 'name'", plugin=impl.plugin_name)
        staged.append(Entry(kind, label, cls, impl.plugin_name, dist, version, tuple(aliases)))

    kwargs = {"register": register} if "register" in impl.argnames else {}
    try:
        impl.function(**kwargs)
    except KeyboardInterrupt:
        raise
    except BaseException as exc:
        problem(impl.plugin_name, dist, f"raised in {kind} registration", exc)
        return
    for entry in staged:
        try:
            registry.add(entry)
        except DuplicateName as exc:
            other = registry.owner(exc.kind, exc.name)
            builtin = other is not None and other.distribution == OWN_DISTRIBUTION
            if other is not None and (builtin or dist == OWN_DISTRIBUTION):  # not shadowed
                intruder = other if not builtin else entry
                if not builtin:
                    registry.replace(entry)
                problem(
                    intruder.plugin, intruder.distribution,
                    f"registered the {exc.kind} name '{exc.name}' of a built-in; the built-in "
                    "is kept and this one is not used", PluginError("rename the plugin"),
                )  # fmt: skip
                continue
            registry.withdraw(exc.kind, exc.name)
            problem(impl.plugin_name, dist, "registered a name another plugin has", exc)
        except PluginError as exc:
            problem(impl.plugin_name, dist, "registered an invalid plugin", exc)
