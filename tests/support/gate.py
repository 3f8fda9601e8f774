"""A classifier whose fit waits for the test: interrupt tests that do not race the machine.

A test that cancels or interrupts a run "after the first task" cannot rely on the run
lasting long enough: a fast machine finishes it first, a slow one not at all.  The ``gate``
entry's fit waits until the test lets it through, so a test decides exactly how many tasks
finish before it acts, on any machine.

It reaches every process of touchbench (the CLI, a service, its job and worker processes)
as a plugin (:mod:`benchmark.catalogue.plugins`): :meth:`Gate.environment` gives the
variables a subprocess needs.  Each fit takes one *pass* (a file the test writes; renaming
it is atomic, so two workers never take the same one) or goes through at once when the gate
is open, and leaves a ``started-*`` file as it begins, so the test can see tasks waiting.
"""

from __future__ import annotations

import os
import time
import uuid
from pathlib import Path
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin

from touchbench.benchmark.catalogue.neural import NeuralSequenceClassifier
from touchbench.benchmark.catalogue.spec import ClassifierSpec

#: The folder of the gate's files, given to every process through the environment.
GATE_VARIABLE = "TOUCHBENCH_TEST_GATE"
#: Longest a fit waits for a pass before it fails (a test that forgot its gate).
LONGEST_WAIT = 600.0
ROOT = Path(__file__).resolve().parents[2]


class GateClassifier(ClassifierMixin, BaseEstimator):
    """Majority class, once the test lets the fit through (see :class:`Gate`).

    ``stubborn`` fits ignore Ctrl-C while they wait, as a fit inside native code does
    (libsvm, a BLAS call): only killing the process stops them.
    """

    def __init__(self, random_state: int | None = None, stubborn: bool = False) -> None:
        self.random_state = random_state
        self.stubborn = stubborn

    def fit(self, X: Any, y: Any) -> GateClassifier:
        Gate(Path(os.environ[GATE_VARIABLE])).wait(ignore_interrupts=self.stubborn)
        labels, counts = np.unique(np.asarray(y), return_counts=True)
        self.classes_ = labels
        self.majority_ = labels[int(np.argmax(counts))]
        self.prior_ = counts / counts.sum()
        return self

    def predict(self, X: Any) -> np.ndarray:
        return np.full(len(X), self.majority_)

    def predict_proba(self, X: Any) -> np.ndarray:
        return np.tile(self.prior_, (len(X), 1))


class GatedNetworkClassifier(NeuralSequenceClassifier):
    """A narrow ``cnn1d`` network (:data:`SMALL`), whose every fit first passes the gate:
    with the gate open, its ``started-*`` files tell the test which fold's training began."""

    def fit(self, X: Any, y: Any, groups: np.ndarray | None = None) -> GatedNetworkClassifier:
        Gate(Path(os.environ[GATE_VARIABLE])).wait()
        super().fit(X, y, groups)
        return self


#: The ``cnn1d`` entry's parameters (a test keeps them equal; the catalogue itself cannot
#: be read here: plugins load while it is being built), with :data:`SMALL` on top.
CNN1D_PARAMS = {"network": "cnn1d", "filters": 32, "kernel": 5, "hidden": 64}
#: A narrow network and few epochs: a quick test.
SMALL = {"filters": 8, "max_epochs": 10}

CLASSIFIERS = (
    *(
        ClassifierSpec(
            id=spec_id,
            weka_command=None,
            family="test",
            description="Test only: majority class once the test lets each fit through",
            factory=GateClassifier,
            params=params,
            probabilities=True,
            needs_scaling=False,
            handles_missing=True,
            handles_nominal=False,
            cost="fast",
            suites=frozenset(),
        )
        for spec_id, params in (("gate", {}), ("gate-stubborn", {"stubborn": True}))
    ),
    ClassifierSpec(
        id="gate-cnn1d",
        weka_command=None,
        family="test",
        description="Test only: cnn1d, each fit once the test lets it through",
        factory=GatedNetworkClassifier,
        params={**CNN1D_PARAMS, **SMALL},
        probabilities=True,
        needs_scaling=False,
        handles_missing=False,
        handles_nominal=False,
        cost="slow",
        suites=frozenset(),
        min_sequence=4,
    ),
)


class Gate:
    """The test's side of the gate: a folder of pass files.

    Parameters
    ----------
    folder : Path
        Created if absent; one per test (``tmp_path``).
    """

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        folder.mkdir(parents=True, exist_ok=True)

    def environment(self) -> dict[str, str]:
        """Variables for a subprocess that should know the ``gate`` entry."""
        path = os.environ.get("PYTHONPATH", "")
        return {
            GATE_VARIABLE: str(self.folder),
            "TOUCHBENCH_PLUGINS": "tests.support.gate",
            "PYTHONPATH": os.pathsep.join(p for p in (str(ROOT), path) if p),
        }

    def let_through(self, n: int = 1) -> None:
        """Let ``n`` more fits through."""
        for _ in range(n):
            (self.folder / f"pass-{uuid.uuid4().hex}").touch()

    def open(self) -> None:
        """Let every fit through from now on."""
        (self.folder / "open").touch()

    def started(self) -> int:
        """How many fits have begun (waiting or through)."""
        return sum(1 for _ in self.folder.glob("started-*"))

    def wait_started(self, n: int, timeout: float = 120.0) -> None:
        """Wait until ``n`` fits have begun."""
        deadline = time.monotonic() + timeout
        while self.started() < n:
            if time.monotonic() > deadline:
                raise AssertionError(f"{self.started()} fits began, not {n}, in {timeout:g} s")
            time.sleep(0.02)

    def wait(self, *, ignore_interrupts: bool = False) -> None:
        """A fit's side: take a pass, or go through an open gate; with ``ignore_interrupts``
        a KeyboardInterrupt does not end the wait."""
        me = uuid.uuid4().hex
        (self.folder / f"started-{me}").touch()
        deadline = time.monotonic() + LONGEST_WAIT
        while time.monotonic() < deadline:
            try:
                if self._take_pass(me):
                    return
                time.sleep(0.02)
            except KeyboardInterrupt:
                if not ignore_interrupts:
                    raise
        raise TimeoutError(f"no pass in {self.folder} after {LONGEST_WAIT:g} s")

    def _take_pass(self, me: str) -> bool:
        """Whether this fit may go: the gate is open, or it took a pass."""
        if (self.folder / "open").exists():
            return True
        for ticket in sorted(self.folder.glob("pass-*")):
            try:
                ticket.rename(self.folder / f"used-{me}")
            except FileNotFoundError:  # another fit took it first
                continue
            return True
        return False
