"""Settings in one place: every ``TOUCHBENCH_*`` variable the code names is a field of
:class:`app.settings.Settings` with its help, the readers that stand beside it (the CLI's,
the catalogue's) read what it reads, and a value a setting refuses is one line naming the
variable."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from tests.support.cli_runner import run_cli
from touchbench.app import environment
from touchbench.app.cli.requests import option_of
from touchbench.app.settings import Settings, SettingsError, get_settings, variable
from touchbench.benchmark.catalogue.plugins import configured_modules

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = ("app", "benchmark", "features", "drivers")


@pytest.fixture
def clean_environment(monkeypatch: pytest.MonkeyPatch) -> pytest.MonkeyPatch:
    """No ``TOUCHBENCH_*`` variable but those the test sets."""
    for name in [name for name in os.environ if name.upper().startswith("TOUCHBENCH_")]:
        monkeypatch.delenv(name)
    get_settings.cache_clear()
    return monkeypatch


def test_every_variable_the_code_names_is_a_setting_with_help() -> None:
    named = set()
    for package in PACKAGES:
        for path in (ROOT / package).rglob("*.py"):
            named |= set(re.findall(r"\bTOUCHBENCH_[A-Z][A-Z_]*[A-Z]\b", path.read_text()))
    declared = {variable(field): info for field, info in Settings.model_fields.items()}
    assert named - set(declared) == set(), "declare these in app.settings.Settings"
    assert {"TOUCHBENCH_DATABASE_URL", "TOUCHBENCH_DEBUG", "TOUCHBENCH_PLUGINS"} <= named
    for name, info in declared.items():
        assert info.description and info.description.endswith("."), name


@pytest.mark.parametrize(
    "value", [None, "", "0", "1", "yes", "No", "TRUE", "off", "f", "on", "y", "t", "n"]
)
def test_the_cli_reads_the_debug_switch_as_the_settings_do(
    value: str | None, clean_environment: pytest.MonkeyPatch
) -> None:
    if value is not None:
        clean_environment.setenv("touchbench_debug", value)
    assert environment.debug() is Settings().debug


@pytest.mark.parametrize(
    "environment_",
    [
        {},
        {"TOUCHBENCH_PLUGINS": "tests.support.gate"},
        {"touchbench_plugins": "tests.support.gate, tests.support.memory_hog"},
        {"TOUCHBENCH_PLUGINS": "a", "Touchbench_Plugins": "b"},
        {"TOUCHBENCH_PLUGINS": ""},
    ],
)
def test_the_catalogue_reads_the_plugins_as_the_settings_do(
    environment_: dict[str, str], clean_environment: pytest.MonkeyPatch
) -> None:
    for name, value in environment_.items():
        clean_environment.setenv(name, value)
    assert configured_modules() == Settings().plugins


def test_putting_a_setting_replaces_every_spelling_of_its_variable(
    clean_environment: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    clean_environment.setenv("TOUCHBENCH_DATABASE_URL", "sqlite:///old.db")
    clean_environment.setenv("touchbench_database_url", "sqlite:///older.db")
    environment.put_setting("database_url", f"sqlite:///{tmp_path / 'new.db'}")
    assert environment.database_url() == Settings().database_url == f"sqlite:///{tmp_path}/new.db"
    assert [name for name in os.environ if name.lower() == "touchbench_database_url"] == [
        "TOUCHBENCH_DATABASE_URL"
    ]


@pytest.mark.parametrize(
    ("name", "value", "words"),
    [
        ("TOUCHBENCH_MAX_TARGETS", "lots", "TOUCHBENCH_MAX_TARGETS: Input should be a valid int"),
        ("touchbench_job_workers", "0", "TOUCHBENCH_JOB_WORKERS: Input should be greater than"),
        ("TOUCHBENCH_DEBUG", "perhaps", "TOUCHBENCH_DEBUG: Input should be a valid boolean"),
    ],
)
def test_a_value_a_setting_refuses_names_the_variable(
    name: str, value: str, words: str, clean_environment: pytest.MonkeyPatch
) -> None:
    clean_environment.setenv(name, value)
    with pytest.raises(SettingsError) as refused:
        get_settings()
    assert str(refused.value).startswith(words) and value not in str(refused.value)
    get_settings.cache_clear()


def test_serve_refuses_a_bad_setting_in_one_line(tmp_path: Path) -> None:
    environment_ = {
        **{k: v for k, v in os.environ.items() if not k.upper().startswith("TOUCHBENCH_")},
        "PYTHONPATH": str(ROOT),
        "TOUCHBENCH_MAX_UPLOAD_MB": "-1",
    }
    cli = [sys.executable, "-m", "touchbench.app.cli.main", "--db", f"sqlite:///{tmp_path}/s.db"]
    done = subprocess.run(
        [*cli, "serve", "--port", "1"],
        env=environment_,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 2, done.stderr
    assert done.stderr == (
        "touchbench: error: TOUCHBENCH_MAX_UPLOAD_MB: Input should be greater than 0\n"
    )


def test_a_commands_options_end_with_its_call(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    """The options a command named for its request's fields do not outlive the call: a
    later refusal in this process is not shown in the words of that command."""
    url = f"sqlite:///{tmp_path / 'o.db'}"
    refused = run_cli(capsys, url, "bench", "nothing", "--max-memory", "lots")
    assert refused.code == 2 and refused.err.startswith("touchbench: error: --max-memory:")
    assert option_of("max_memory_mb") == "--max-memory-mb"
