"""Classifiers a caller brings for the runs it carries out in this process: the Python API's
scikit-learn estimators (``touchbench.bench(..., classifiers=[MyEstimator()])``).

They are catalogue specs that live as long as the call that adds them
(:func:`own_specs_added`) and are seen by every run planned or executed inside it, through
:func:`app.services.tuning.run_specs`, as a plugin module's are through the catalogue.  The
store keeps only their ids: a run with them is resumed by the process that knows them.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from contextvars import ContextVar
from types import MappingProxyType
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from touchbench.benchmark.catalogue import ClassifierSpec

_OWN: ContextVar[Mapping[str, ClassifierSpec]] = ContextVar(
    "own_specs", default=MappingProxyType({})
)


def own_specs() -> Mapping[str, ClassifierSpec]:
    """The specs the current call added, by id (none outside :func:`own_specs_added`)."""
    return _OWN.get()


@contextmanager
def own_specs_added(specs: Mapping[str, ClassifierSpec]) -> Iterator[None]:
    """Make ``specs`` known to the runs planned and executed inside the ``with`` block."""
    token = _OWN.set(MappingProxyType({**_OWN.get(), **specs}))
    try:
        yield
    finally:
        _OWN.reset(token)
