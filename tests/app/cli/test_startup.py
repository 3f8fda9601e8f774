"""The CLI's start-up: each command imports its own module only, and the table in
``app.cli.main`` that lists the commands without importing them says what they say."""

from __future__ import annotations

import importlib
import inspect
import os
import pkgutil
import subprocess
import sys
from pathlib import Path

import pytest
import typer

import touchbench.app.cli
from tests.support.cli_runner import run_cli
from touchbench.app.cli.lazy import LazyGroup
from touchbench.app.cli.main import COMMANDS, main
from touchbench.app.environment import DEFAULT_DATABASE_URL, database_url
from touchbench.app.settings import Settings

ROOT = Path(__file__).resolve().parents[3]
TOUCHBENCH = Path(sys.executable).with_name("touchbench")

#: Modules that no command's start-up needs before it is chosen (the store, the engine's
#: libraries, the request and response types).
HEAVY = (
    "sqlalchemy",
    "numpy",
    "pydantic",
    "touchbench.app.store",
    "touchbench.app.services",
    "touchbench.app.schemas",
)
#: Every module that defines commands.
COMMAND_MODULES = tuple(dict.fromkeys(command.module for command in COMMANDS))


def _first_paragraph(help_text: str) -> str:
    return " ".join(inspect.cleandoc(help_text).split("\n\n")[0].split())


def test_the_table_is_what_the_modules_register() -> None:
    """Names, modules and one-line help of the table are the commands' own (the table's
    order is the order of the group's help page)."""
    registered = []
    for module_name in COMMAND_MODULES:
        holder = typer.Typer()
        importlib.import_module(module_name).register(holder)
        for info in holder.registered_commands:
            command = typer.main.get_command_from_info(
                info, pretty_exceptions_short=True, rich_markup_mode=holder.rich_markup_mode
            )
            assert command.short_help is None and not command.hidden, command.name
            assert not getattr(command, "rich_help_panel", None), command.name
            registered.append((command.name, module_name, _first_paragraph(command.help or "")))
    table = [tuple(command) for command in COMMANDS]
    assert len({name for name, *_ in table}) == len(table)
    assert sorted(table) == sorted(registered)


def test_every_module_with_commands_is_in_the_table() -> None:
    defining = set()
    for module in pkgutil.iter_modules(touchbench.app.cli.__path__, "touchbench.app.cli."):
        if hasattr(importlib.import_module(module.name), "register"):
            defining.add(module.name)
    assert defining == set(COMMAND_MODULES)


def test_the_help_page_reads_as_the_commands_own_would(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """The page drawn from the table equals the page drawn from the commands themselves."""
    url = f"sqlite:///{tmp_path / 'h.db'}"
    from_table = run_cli(capsys, url, "--help")
    monkeypatch.setattr(LazyGroup, "format_help", typer.core.TyperGroup.format_help)
    from_commands = run_cli(capsys, url, "--help")
    assert from_table.code == from_commands.code == 0
    assert "delete-model" in from_table.out and "Predict every touch" in from_table.out
    assert from_table.out == from_commands.out


def test_a_misspelt_command_is_refused_with_a_suggestion(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    result = run_cli(capsys, f"sqlite:///{tmp_path / 'm.db'}", "dataset")
    assert result.code == 2
    assert result.err == (
        "touchbench: error: No such command 'dataset'. Did you mean 'datasets'? "
        "(see 'touchbench --help')\n"
    )


@pytest.mark.parametrize(
    "environment",
    [
        {},
        {"TOUCHBENCH_DATABASE_URL": "sqlite:///upper.db"},
        {"touchbench_database_url": "sqlite:///lower.db"},
        {"Touchbench_Database_Url": "sqlite:///mixed.db"},
        {"TOUCHBENCH_DATABASE_URL": "sqlite:///a.db", "touchbench_database_url": "sqlite:///b.db"},
        {"touchbench_database_url": "sqlite:///b.db", "TOUCHBENCH_DATABASE_URL": "sqlite:///a.db"},
        {"TOUCHBENCH_DATABASE_URL": ""},
        {"TOUCHBENCH_DATABASE_URLS": "sqlite:///not-this.db"},
    ],
)
def test_the_commands_read_the_store_url_as_the_settings_do(
    environment: dict[str, str], monkeypatch: pytest.MonkeyPatch
) -> None:
    for name in [name for name in os.environ if name.upper().startswith("TOUCHBENCH_")]:
        monkeypatch.delenv(name)
    for name, value in environment.items():
        monkeypatch.setenv(name, value)
    assert database_url() == Settings().database_url
    if not environment:
        assert database_url() == DEFAULT_DATABASE_URL


def test_without_db_a_command_uses_the_environment_then_the_current_folder(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("TOUCHBENCH_DATABASE_URL", raising=False)
    assert main(["datasets", "--json"]) == 0
    assert (tmp_path / "touchbench.db").is_file()
    monkeypatch.setenv("TOUCHBENCH_DATABASE_URL", f"sqlite:///{tmp_path / 'elsewhere.db'}")
    assert main(["datasets", "--json"]) == 0
    assert (tmp_path / "elsewhere.db").is_file()


def _imported(*args: str, cwd: Path, program: tuple[str, ...] = (str(TOUCHBENCH),)) -> set[str]:
    """The modules that the console script ``touchbench ARGS`` (or ``program ARGS``)
    imports, from Python's own import log (``-X importtime``), in a fresh process."""
    environment = {**os.environ, "PYTHONPROFILEIMPORTTIME": "1", "PYTHONPATH": str(ROOT)}
    environment.pop("TOUCHBENCH_DATABASE_URL", None)
    done = subprocess.run(
        [*program, *args],
        capture_output=True,
        text=True,
        cwd=cwd,
        env=environment,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    log = [line for line in done.stderr.splitlines() if line.startswith("import time:")]
    assert log, "the import log is empty: PYTHONPROFILEIMPORTTIME was not honoured"
    return {line.rsplit("|", 1)[1].strip() for line in log} - {"imported package"}


def _heavy(modules: set[str]) -> set[str]:
    return {m for m in modules if m.split(".")[0] in HEAVY or m.startswith(HEAVY)}


@pytest.mark.parametrize("option", ["--version", "--help", "-h"])
def test_version_and_help_import_no_command(option: str, tmp_path: Path) -> None:
    imported = _imported(option, cwd=tmp_path)
    assert "touchbench.app.cli.main" in imported and "typer" in imported
    assert _heavy(imported) == set()
    assert imported.isdisjoint(COMMAND_MODULES)


def test_a_command_imports_its_own_module_only(tmp_path: Path) -> None:
    imported = _imported("datasets", cwd=tmp_path)  # the store in the current folder
    assert "touchbench.app.cli.listing" in imported and "sqlalchemy" in imported
    assert imported & set(COMMAND_MODULES) == {"touchbench.app.cli.listing"}
    # Once the store exists (the first command made and migrated it), listing it reads one
    # table through sqlite3 alone: no SQLAlchemy, no NumPy.
    again = _imported("datasets", cwd=tmp_path)
    assert "touchbench.app.store.listing" in again and "sqlite3" in again
    assert {
        "sqlalchemy",
        "numpy",
        "touchbench.app.store.tables",
        "touchbench.app.store.database",
    } & again == set()
    assert "pydantic_settings" not in imported  # the store's URL is all a command reads
    help_only = _imported("train", "--help", cwd=tmp_path)
    assert help_only & set(COMMAND_MODULES) == {"touchbench.app.cli.models"}


def test_the_chosen_commands_module_is_frozen_once(tmp_path: Path) -> None:
    """What a command's module made is out of the cyclic collector's reach once imported,
    and calling the CLI again in the same process freezes nothing more."""
    script = (
        "import gc, sys\n"
        "from touchbench.app.cli.main import main\n"
        "assert main(sys.argv[1:]) == 0\n"
        "from touchbench.app.cli.listing import datasets_command\n"
        "assert gc.is_tracked(datasets_command)\n"
        "frozen = not any(o is datasets_command for o in gc.get_objects())\n"
        "made_since = []\n"
        "assert main(sys.argv[1:]) == 0\n"
        "print(frozen, any(o is made_since for o in gc.get_objects()))\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", script, "--db", f"sqlite:///{tmp_path / 's.db'}", "datasets"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["True", "True"]


def test_the_job_process_help_imports_no_store(tmp_path: Path) -> None:
    program = (sys.executable, "-m", "touchbench.app.jobs.process")
    imported = _imported("--help", cwd=tmp_path, program=program)
    assert "argparse" in imported
    assert _heavy(imported) == set()
