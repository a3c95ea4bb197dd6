"""The ``retarget`` command: core verbs plus the commands plugins register.

User errors (:class:`retarget.errors.RetargetError`) print as one readable message and exit 2;
no traceback. Plugins are loaded once per invocation; a broken plugin is a warning unless
``--strict-plugins`` / ``RETARGET_STRICT_PLUGINS=1``.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import traceback
import warnings
from collections.abc import Sequence

import retarget
from retarget.cli import (
    average_cmd,
    blend_cmd,
    eval_cmd,
    export_cmd,
    play_cmd,
    plugins_cmd,
    pretrained_cmd,
    recipe_cmd,
    serve_cmd,
    stream_cmd,
    train_cmd,
    view_cmd,
)
from retarget.errors import PluginError, RetargetError
from retarget.kinds import Command
from retarget.registry import Registry
from retarget.registry.loader import PluginLoadWarning, load_plugins, strict_from_env

EXIT_USER_ERROR = 2


class _DefaultsFormatter(argparse.HelpFormatter):
    """Appends ``(default: X)`` to an option's help unless it already names its default or
    has none worth saying (None, False, empty)."""

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        default = action.default
        if (
            "default" in text
            or default in (None, False, [], "")
            or default is argparse.SUPPRESS
            or not action.option_strings
        ):
            return text
        return f"{text} (default: %(default)s)"


class _Parser(argparse.ArgumentParser):
    """Subcommand parsers whose help shows every option's default."""

    def __init__(self, *args, **kwargs) -> None:
        kwargs.setdefault("formatter_class", _DefaultsFormatter)
        super().__init__(*args, **kwargs)


def build_parser(registry: Registry) -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="retarget",
        description="Drive physically simulated avatars of any body shape from VR headset "
        "signals: train, evaluate and inspect policies and plugins.",
    )
    parser.add_argument("--version", action="version", version=f"retarget {retarget.__version__}")
    parser.add_argument(
        "--strict-plugins",
        action="store_true",
        help="fail if any plugin cannot be loaded (also RETARGET_STRICT_PLUGINS=1)",
    )
    sub = parser.add_subparsers(dest="verb", metavar="COMMAND", parser_class=_Parser)
    plugins_cmd.add_parser(sub)
    pretrained_cmd.add_parser(sub)
    recipe_cmd.add_parser(sub)
    train_cmd.add_parser(sub)
    eval_cmd.add_parser(sub)
    play_cmd.add_parser(sub)
    export_cmd.add_parser(sub)
    average_cmd.add_parser(sub)
    blend_cmd.add_parser(sub)
    serve_cmd.add_parser(sub)
    stream_cmd.add_parser(sub)
    view_cmd.add_parser(sub)
    for name in registry.names("command"):
        entry = registry.get("command", name)
        _add_plugin_command(sub, entry.cls, entry.plugin, entry.distribution)
    return parser


def _add_plugin_command(
    sub: argparse._SubParsersAction, cls: type[Command], plugin: str, dist: str
) -> None:
    command = cls()
    parser = sub.add_parser(cls.name, help=cls.help or cls.summary(), description=cls.__doc__)
    command.add_arguments(parser)

    def handler(args: argparse.Namespace, registry: Registry) -> int:
        command.connect(registry)
        try:
            return int(command.run(args) or 0)
        except (RetargetError, KeyboardInterrupt):
            raise
        except Exception as exc:  # the plugin's bug: name it, keep the traceback in a file
            if os.environ.get("RETARGET_DEBUG"):
                raise
            raise PluginError(
                f"command '{cls.name}' failed: {type(exc).__name__}: {exc}",
                plugin=f"{plugin} from {dist}",
                hint=f"the full traceback is in {_save_traceback()}",
            ) from exc

    parser.set_defaults(handler=handler, plugin_name=plugin, plugin_dist=dist)


def _load(strict: bool) -> Registry:
    from retarget.cli.console import warning
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", PluginLoadWarning)
        registry = load_plugins(strict=strict)
    for item in caught:
        if issubclass(item.category, PluginLoadWarning):
            warning(str(item.message))
        else:
            warnings.showwarning(item.message, item.category, item.filename, item.lineno)
    return registry


def _save_traceback() -> str:
    """Write the exception being handled to a file and return its path: the terminal gets one
    line, a bug report gets the whole story."""
    fd, path = tempfile.mkstemp(prefix="retarget-traceback-", suffix=".txt")
    with os.fdopen(fd, "w", encoding="utf-8") as fh:
        fh.write(f"retarget {retarget.__version__}, python {sys.version.split()[0]}\n")
        fh.write(f"argv: {sys.argv!r}\n\n")
        traceback.print_exc(file=fh)
    return path


def main(argv: Sequence[str] | None = None) -> int:
    from retarget.cli.console import error

    argv = list(sys.argv[1:] if argv is None else argv)
    if argv == ["--version"]:  # answered before any plugin is loaded
        print(f"retarget {retarget.__version__}")
        return 0
    strict = "--strict-plugins" in argv or strict_from_env()
    try:
        registry = _load(strict)
        parser = build_parser(registry)
        args = parser.parse_args(argv)
        if getattr(args, "handler", None) is None:
            parser.print_help()
            return 0
        return int(args.handler(args, registry) or 0)
    except RetargetError as exc:
        error(exc.format())
        return EXIT_USER_ERROR
    except KeyboardInterrupt:
        error("interrupted")
        return 130
    except Exception as exc:
        if os.environ.get("RETARGET_DEBUG"):
            raise
        args = locals().get("args")
        plugin = getattr(args, "plugin_name", None)
        where = f" in plugin '{plugin}' from {args.plugin_dist}" if plugin else ""
        verb = " ".join(["retarget", *argv[:1]])
        saved = _save_traceback()
        error(
            f"unexpected failure of '{verb}'{where}: {type(exc).__name__}: {exc}\n"
            f"  the full traceback is in {saved} (RETARGET_DEBUG=1 raises it instead)"
        )
        return 1


if __name__ == "__main__":
    raise SystemExit(main())
