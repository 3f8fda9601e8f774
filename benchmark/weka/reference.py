"""Run the real WEKA (Debian's ``weka`` package) to compare touchbench with it.

Used by ``perf/weka_agreement.py`` and by the tests that check WEKA-named entries against
WEKA itself.  Nothing in touchbench's own path needs Java.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from touchbench.benchmark.errors import ConfigurationError

#: Where Debian's ``weka`` package puts the jar and WEKA's example data files.
WEKA_JARS = ("/usr/share/java/weka.jar", "/usr/share/java/weka-3.6.14.jar")
WEKA_DATA = Path("/usr/share/doc/weka/examples")

_CORRECT = re.compile(r"Correctly Classified Instances\s+\S+\s+([0-9.]+)\s*%")
_PREDICTION = re.compile(r"^\s*\d+\s+\S+\s+(\d+):")


def weka_jar() -> str | None:
    """The WEKA jar (``$WEKA_JAR`` or Debian's), or None when WEKA or Java is absent."""
    candidates = [os.environ.get("WEKA_JAR", ""), *WEKA_JARS]
    if shutil.which("java") is None:
        return None
    return next((c for c in candidates if c and Path(c).is_file()), None)


def run_weka(arguments: Sequence[str], *, timeout: float = 600.0) -> str:
    """Run ``java -cp weka.jar ARGUMENTS`` and return its standard output.

    Raises
    ------
    ConfigurationError
        WEKA is not installed, or it failed (its last error line is quoted).
    """
    jar = weka_jar()
    if jar is None:
        raise ConfigurationError(
            "WEKA is not installed (apt-get install weka default-jre-headless)"
        )
    completed = subprocess.run(
        ["java", "-Xmx1g", "-cp", jar, *arguments],
        capture_output=True,
        text=True,
        timeout=timeout,
        check=False,
    )
    if completed.returncode != 0 or "Exception" in completed.stderr:
        lines = (completed.stderr or completed.stdout).strip().splitlines() or ["no output"]
        raise ConfigurationError(f"WEKA failed on {shlex.join(arguments)}: {lines[-1]}")
    return completed.stdout


def cross_validated_accuracy(
    command: str, data: Path, *, folds: int = 10, seed: int = 1, class_index: str = "last"
) -> float:
    """WEKA's stratified cross-validation accuracy (percent) of a command on an ARFF file.

    Parameters
    ----------
    command : str
        A WEKA command line, class then options (``"weka.classifiers.trees.J48 -C 0.25"``).
    data : Path
        ARFF file; the last attribute is the class.
    folds, seed : int
        WEKA's ``-x`` and ``-s``.
    class_index : str
        WEKA's ``-c``: ``"last"``, ``"first"`` or a 1-based index.
    """
    scheme, *options = shlex.split(command)
    arguments = ["-t", str(data), "-c", class_index, "-x", str(folds), "-s", str(seed), "-o"]
    output = run_weka([scheme, *arguments, *options])
    match = _CORRECT.search(output.split("=== Stratified cross-validation ===")[-1])
    if match is None:
        raise ConfigurationError(f"no accuracy in WEKA's output for {command} on {data}")
    return float(match.group(1))


def predictions(command: str, train: Path, test: Path, *, class_index: str = "last") -> np.ndarray:
    """Class codes (0-based) WEKA predicts for the instances of ``test``, in order."""
    scheme, *options = shlex.split(command)
    arguments = ["-t", str(train), "-T", str(test), "-c", class_index, "-p", "0"]
    output = run_weka([scheme, *arguments, *options])
    codes = [int(m.group(1)) - 1 for line in output.splitlines() if (m := _PREDICTION.match(line))]
    return np.asarray(codes, dtype=np.int64)
