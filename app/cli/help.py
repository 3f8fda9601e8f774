"""typer's help pages, made to read as click's do.

typer 0.29 shows every flag's type as ``<bool>`` and other types as ``<int>``, ``<path>``,
``<list[Path]>``; writes a required argument as ``{NAME}`` in the usage line; and keeps the
source's line breaks inside a docstring's later paragraphs and in the command list.  Mature
command lines print nothing for a flag and the metavar or an upper-case type otherwise,
write ``NAME`` / ``[NAME]`` / ``NAME...``, and reflow paragraphs.  :func:`install` patches
those spots of typer once, at import of the CLI; nothing else of typer is touched.  typer's
``rich_utils`` (rich's Markdown and its parser: a twentieth of a second) is imported and
patched only when a help page is drawn, as typer itself imports it.
"""

from __future__ import annotations

# Imports inside functions: start-up time: typer's internals load only when a help page
# is drawn.
import inspect
from typing import Any

#: typer's type labels -> the words click uses.
_TYPE_WORDS = {"int": "INTEGER", "float": "NUMBER", "str": "TEXT", "path": "PATH"}


def install() -> None:
    """Patch typer's help rendering (idempotent)."""
    from typer.core import TyperArgument, TyperCommand, TyperGroup, TyperOption

    def option_type(self: TyperOption, ctx: Any) -> str | None:
        if self.is_flag or self.count:
            return None
        if self.metavar is not None:
            return str(self.metavar)
        label = str(self.display_type(ctx)).strip("<>")
        word = _TYPE_WORDS.get(label, label.upper())
        return f"{word}..." if self.nargs != 1 else word

    def argument_type(self: TyperArgument, ctx: Any) -> str | None:
        return None  # the name column (its metavar) already says what it is

    def usage_name(self: TyperArgument) -> str:
        name = str(self.display_name_raw)
        name = name if self.required else f"[{name}]"
        return name + ("..." if self.nargs != 1 and not name.endswith("...") else "")

    TyperOption.display_type_rich = option_type  # type: ignore[method-assign]
    TyperArgument.display_type_rich = argument_type  # type: ignore[method-assign,assignment]
    TyperArgument._usage_display_name = usage_name  # type: ignore[method-assign]
    for command_class in (TyperCommand, TyperGroup):
        if not getattr(command_class.format_help, "_touchbench_patched", False):
            command_class.format_help = _patching_first(command_class.format_help)  # type: ignore[method-assign]


def _patching_first(format_help: Any) -> Any:
    """``format_help`` of a typer command, patching ``rich_utils`` before its first page."""

    def patched(self: Any, ctx: Any, formatter: Any) -> Any:
        _patch_rich_utils()
        return format_help(self, ctx, formatter)

    patched._touchbench_patched = True  # type: ignore[attr-defined]
    return patched


def _patch_rich_utils() -> None:
    """Make typer's rich help show a command's first paragraph and reflow paragraphs."""
    from typer import rich_utils

    if getattr(rich_utils, "_touchbench_patched", False):
        return
    command_help = rich_utils._make_command_help

    def short_help(*, help_text: str, markup_mode: Any) -> Any:
        first = inspect.cleandoc(help_text).split("\n\n")[0]
        return command_help(help_text=" ".join(first.split()), markup_mode=markup_mode)

    def reflow(paragraphs: list[str], markup_mode: Any) -> str:
        return "\n\n".join(
            paragraph if paragraph.startswith("\b") else " ".join(paragraph.split())
            for paragraph in paragraphs
        )

    rich_utils._make_command_help = short_help
    rich_utils._fix_linebreaks = reflow
    rich_utils._touchbench_patched = True  # type: ignore[attr-defined]
