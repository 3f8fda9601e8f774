"""skops is imported without importing every package of scikit-learn, and trusts the same
estimators as when imported plainly."""

from __future__ import annotations

import json
from pathlib import Path

from tests.support.processes import run_script


def test_skops_trusts_the_same_estimators_without_importing_sklearn_tests(
    tmp_path: Path,
) -> None:
    script = (
        "import json, sys\n"
        "from touchbench.benchmark.skops_import import import_skops_io\n"
        "import_skops_io()\n"
        "from skops.io._trusted_types import SKLEARN_ESTIMATOR_TYPE_NAMES as trusted\n"
        "loaded = [m for m in ('sklearn.tests', 'torch') if m in sys.modules]\n"
        "from sklearn.utils import all_estimators\n"
        "from skops.io._utils import get_type_name\n"
        "plain = [get_type_name(c) for _, c in all_estimators()]\n"
        "plain = [name for name in plain if name.startswith('sklearn.')]\n"
        "print(json.dumps({'loaded': loaded, 'trusted': trusted, 'plain': plain}))\n"
    )
    done = run_script(script, tmp_path)
    found = json.loads(done.stdout)
    assert found["loaded"] == []
    assert len(found["trusted"]) > 100 and found["trusted"] == found["plain"]
