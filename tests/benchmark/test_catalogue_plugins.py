"""Classifiers from plugin modules named in TOUCHBENCH_PLUGINS."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from touchbench.benchmark.catalogue.plugins import plugin_specs
from touchbench.benchmark.errors import ConfigurationError

ROOT = Path(__file__).resolve().parents[2]


def test_a_plugin_module_gives_its_specs() -> None:
    specs = plugin_specs(["rf", "nb"], "tests.support.gate, ")
    assert [spec.id for spec in specs] == ["gate", "gate-stubborn", "gate-cnn1d"]


@pytest.mark.parametrize(
    ("modules", "message"),
    [
        ("tests.no_such_module", "plugin tests.no_such_module (in TOUCHBENCH_PLUGINS) cannot be"),
        ("tests", "plugin tests has no CLASSIFIERS sequence"),
        (
            "tests.support.gate,tests.support.gate",
            "plugin tests.support.gate: classifier id 'gate' is taken",
        ),
    ],
)
def test_a_bad_plugin_is_refused_in_one_line(modules: str, message: str) -> None:
    with pytest.raises(ConfigurationError, match="^" + re.escape(message)):
        plugin_specs(["rf"], modules)


def test_an_id_of_the_catalogue_cannot_be_taken() -> None:
    with pytest.raises(ConfigurationError, match="classifier id 'gate' is taken"):
        plugin_specs(["gate"], "tests.support.gate")


def _classifiers(tmp_path: Path, plugins: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "touchbench.app.cli.main", "classifiers", "--json"],
        env={**os.environ, "PYTHONPATH": str(ROOT), "TOUCHBENCH_PLUGINS": plugins},
        capture_output=True,
        text=True,
        cwd=tmp_path,
        check=False,
    )


def test_the_cli_lists_a_plugin_entry(tmp_path: Path) -> None:
    listing = _classifiers(tmp_path, "tests.support.gate")
    assert listing.returncode == 0, listing.stderr
    assert "gate" in {entry["id"] for entry in json.loads(listing.stdout)["classifiers"]}


def test_the_cli_refuses_a_missing_plugin_in_one_line(tmp_path: Path) -> None:
    listing = _classifiers(tmp_path, "tests.no_such_module")
    assert listing.returncode == 2
    assert listing.stderr.startswith("touchbench: error: plugin tests.no_such_module")
    assert len(listing.stderr.strip().splitlines()) == 1
