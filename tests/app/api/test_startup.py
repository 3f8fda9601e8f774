"""The service's start-up: building the application (its API and its web pages) imports no
library that only some requests need (the statistics, the signal processing, the
classifiers)."""

from __future__ import annotations

from pathlib import Path

from tests.support.processes import run_script

#: Loaded by the requests that use them, never by the application's routes at start.
ON_DEMAND = ("scipy.stats", "scipy.signal", "sklearn", "xgboost", "pandas", "matplotlib", "torch")


def test_the_application_imports_no_library_a_request_may_not_need(tmp_path: Path) -> None:
    script = (
        "import sys\n"
        "import touchbench.app.main\n"
        f"print(' '.join(m for m in {ON_DEMAND!r} if m in sys.modules))\n"
    )
    done = run_script(script, tmp_path)
    assert done.stdout.split() == []
