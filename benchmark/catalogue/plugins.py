"""Classifiers from outside the catalogue: modules named in ``TOUCHBENCH_PLUGINS``.

A researcher's own classifier joins every run, listing and service of touchbench when the
environment names the module that describes it::

    TOUCHBENCH_PLUGINS=mylab.touch_models touchbench bench robot -c rf,mylab-cnn

Each module (comma-separated, importable where touchbench runs: the CLI, the service, its
job and worker processes all inherit the environment) has ``CLASSIFIERS``, a sequence of
:class:`~benchmark.catalogue.spec.ClassifierSpec` whose factories are module-level classes
or functions, so that they pickle by reference into the worker processes.  Their entries
belong to the ``all`` suite and to the suites they name.

This module is where the variable is read: the catalogue is built when it is imported, in
every process that names classifiers (the CLI, the service, job, engine and Dask worker
processes), and the environment is what reaches them all.  The app's settings declare the
variable with its help (:attr:`app.settings.Settings.plugins`) and read it the same way.
"""

from __future__ import annotations

import importlib
import os
from collections.abc import Iterable, Sequence

from touchbench.benchmark.catalogue.spec import ClassifierSpec
from touchbench.benchmark.errors import ConfigurationError

#: The environment variable that names the plugin modules.
PLUGINS_VARIABLE = "TOUCHBENCH_PLUGINS"


def configured_modules() -> str:
    """:data:`PLUGINS_VARIABLE`'s value (empty when unset), its name matched in any case
    and the later of two spellings winning, as the app's settings read it."""
    wanted = PLUGINS_VARIABLE.lower()
    found = [value for name, value in os.environ.items() if name.lower() == wanted]
    return found[-1] if found else ""


def plugin_specs(known: Iterable[str], modules: str | None = None) -> tuple[ClassifierSpec, ...]:
    """The specs of the plugin modules ``modules`` (default: :func:`configured_modules`).

    Parameters
    ----------
    known : iterable of str
        Ids already taken (the catalogue's): a plugin may not take one.
    modules : str, optional
        Comma-separated module names.

    Raises
    ------
    ConfigurationError
        A module that cannot be imported, has no ``CLASSIFIERS``, or gives an id that is
        taken or a value that is not a spec.
    """
    names = configured_modules() if modules is None else modules
    taken = set(known)
    specs: list[ClassifierSpec] = []
    for name in (part.strip() for part in names.split(",")):
        if not name:
            continue
        for spec in _module_specs(name):
            if spec.id in taken:
                raise ConfigurationError(
                    f"plugin {name}: classifier id '{spec.id}' is taken; give it another"
                )
            taken.add(spec.id)
            specs.append(spec)
    return tuple(specs)


def _module_specs(name: str) -> Sequence[ClassifierSpec]:
    try:
        module = importlib.import_module(name)
    except ImportError as error:
        raise ConfigurationError(
            f"plugin {name} (in {PLUGINS_VARIABLE}) cannot be imported: {error}"
        ) from None
    specs = getattr(module, "CLASSIFIERS", None)
    if specs is None:
        raise ConfigurationError(f"plugin {name} has no CLASSIFIERS sequence")
    for spec in specs:
        if not isinstance(spec, ClassifierSpec):
            raise ConfigurationError(
                f"plugin {name}: CLASSIFIERS holds a {type(spec).__name__}, not a ClassifierSpec"
            )
    return tuple(specs)
