"""A command group whose commands' modules are imported only when a command is chosen.

The commands' modules import SQLAlchemy, NumPy, pydantic and the store; ``touchbench
--version``, ``touchbench --help`` and each command should pay only for what it uses.
:class:`LazyGroup` knows its commands from a table of :class:`Subcommand` (name, module,
one-line help): it lists them from the table alone, and the first time a command is looked up
(to be run, or to show its own help) it imports the command's module and builds the command
as typer does."""

from __future__ import annotations

import gc
import sys
from collections.abc import Iterator, MutableMapping
from typing import TYPE_CHECKING, Any, ClassVar, NamedTuple

import typer
from typer.core import TyperCommand, TyperGroup
from typer.main import get_command_from_info, get_command_name
from typer.models import CommandInfo

if TYPE_CHECKING:
    from typer._click import Command  # the click that typer vendors and builds commands of


class Subcommand(NamedTuple):
    """One command of a :class:`LazyGroup`.

    Attributes
    ----------
    name : str
        The command's name on the command line.
    module : str
        The module whose ``register(app: typer.Typer)`` adds the command (with others).
    help : str
        The one-line help the group's page lists: the first paragraph of the command's own
        help, on one line.
    """

    name: str
    module: str
    help: str


class LazyCommands(MutableMapping[str, "Command"]):
    """A group's commands by name, in the table's order; looking one up imports its module
    (once) and builds that command (once).

    Parameters
    ----------
    subcommands : tuple of Subcommand
        The commands, in the order the group lists them.
    rich_markup_mode : str or None
        The group's markup mode, which typer gives every command it builds.
    """

    def __init__(self, subcommands: tuple[Subcommand, ...], rich_markup_mode: Any) -> None:
        self._modules = {command.name: command.module for command in subcommands}
        self._rich_markup_mode = rich_markup_mode
        self._registered: dict[str, CommandInfo] = {}
        self._built: dict[str, Command] = {}

    def __getitem__(self, name: str) -> Command:
        command = self._built.get(name)
        if command is None:
            if name not in self._registered:
                self._register(self._modules[name])
            command = get_command_from_info(
                self._registered[name],
                pretty_exceptions_short=True,  # typer's default (app.cli.main prints errors itself)
                rich_markup_mode=self._rich_markup_mode,
            )
            self._built[name] = command
        return command

    def __setitem__(self, name: str, command: Command) -> None:
        self._built[name] = command

    def __delitem__(self, name: str) -> None:
        del self._built[name]
        self._modules.pop(name, None)

    def __iter__(self) -> Iterator[str]:
        yield from self._modules
        yield from (name for name in self._built if name not in self._modules)

    def __len__(self) -> int:
        return len(self._modules.keys() | self._built.keys())

    def _register(self, module_name: str) -> None:
        """Import ``module_name`` and keep what its ``register`` adds, by command name."""
        first_import = module_name not in sys.modules
        # As an import statement does (importlib.import_module would not show the module
        # itself in ``python -X importtime``, the tool to read start-up with).
        module = __import__(module_name, fromlist=["register"])
        if first_import:
            # What the import made lives as long as the process: out of the cyclic
            # collector's reach, as app.cli.main explains.  Once per module, so that a
            # process calling the CLI again and again does not freeze its own garbage.
            gc.freeze()
        holder = typer.Typer()
        module.register(holder)
        for info in holder.registered_commands:
            assert info.callback is not None, f"{module_name} registers a command without code"
            self._registered[info.name or get_command_name(info.callback.__name__)] = info


class LazyGroup(TyperGroup):
    """A typer group of the commands in :attr:`subcommands`, their modules imported lazily.

    Give a subclass as ``typer.Typer(cls=...)``.  Its help page lists the commands with the
    table's one-line help, importing nothing; everything else (running a command, its help,
    ``commands``, a suggestion for a misspelt name) behaves as a :class:`TyperGroup` of the
    same commands.
    """

    #: The commands, in the order the help page lists them.
    subcommands: ClassVar[tuple[Subcommand, ...]] = ()

    def __init__(self, **attrs: Any) -> None:
        super().__init__(**attrs)
        commands = LazyCommands(self.subcommands, self.rich_markup_mode)
        commands.update(self.commands)  # any that the Typer itself registered
        self.commands = commands
        self._listing = False

    def list_commands(self, ctx: typer.Context) -> list[str]:  # type: ignore[override]
        return list(self.commands)

    def get_command(self, ctx: typer.Context, cmd_name: str) -> Command | None:  # type: ignore[override]
        if self._listing:
            summary = next((c for c in self.subcommands if c.name == cmd_name), None)
            if summary is not None:
                return TyperCommand(name=summary.name, short_help=summary.help)
        return super().get_command(ctx, cmd_name)

    def format_help(self, ctx: typer.Context, formatter: Any) -> None:  # type: ignore[override]
        """The group's help page, listing its commands from the table."""
        self._listing = True
        try:
            super().format_help(ctx, formatter)
        finally:
            self._listing = False
