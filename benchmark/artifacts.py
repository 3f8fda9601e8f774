"""Model artifacts that cannot run code when they are loaded.

A model is written with :mod:`skops.io`, which stores an object tree of known node kinds
instead of a pickle's program.  Before anything is loaded, every type the artifact names
is checked: it must be a class (never a function) defined in a package touchbench's
models are made of (:data:`TRUSTED_PACKAGES`).  An artifact that names anything else (a
crafted ``os.system``, ``subprocess.Popen``, ``builtins.eval``...) is refused before a
single object is built, whoever wrote it into the store.
"""

from __future__ import annotations

import importlib
import io
import json
import zipfile
from typing import Any

from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.extras import EXTRA_OF, require
from touchbench.benchmark.skops_import import import_skops_io

#: Format tag written into every artifact, checked on load.
ARTIFACT_FORMAT = "touchbench-model/1"
#: Packages whose classes a model may be made of.
TRUSTED_PACKAGES = frozenset(
    {
        "touchbench.benchmark",
        "sklearn",
        "numpy",
        "scipy",
        "xgboost",
        "lightgbm",
        "catboost",
        "skmultilearn",
        "wittgenstein",
        "imodels",
    }
)
#: Types and functions outside those packages, or functions inside them, that models hold
#: and that cannot do harm whatever their arguments (a crafted artifact could otherwise
#: make a model call a function that opens files or runs code).
TRUSTED_NAMES = frozenset(
    {
        "collections.OrderedDict",  # LightGBM's boosters keep their parameters in one
        "functools.partial",  # histogram boosting's input check ...
        "sklearn.utils.validation.check_array",  # ... binds this function
        # aeon's rockets as sequence classifiers fit them: kernels as plain arrays.  Only
        # these two: aeon's other transforms hold compiled functions and generators.
        "aeon.transformations.collection.convolution_based._minirocket.MiniRocket",
        "aeon.transformations.collection.convolution_based._multirocket.MultiRocket",
    }
)
#: Classes of trusted packages that touch files, never loaded all the same (a memory-mapped
#: array or an ``.npz`` archive would open a path the artifact names).
REFUSED_TYPES = frozenset({"numpy.memmap", "numpy.lib.npyio.NpzFile", "numpy.lib.npyio.DataSource"})
#: Packages that were once installed under another name: artifacts written before
#: touchbench became one import name call its classes ``benchmark.weka.j48.J48``.
MOVED_PACKAGES = {"benchmark": "touchbench.benchmark"}


def dumps_artifact(content: dict[str, Any]) -> bytes:
    """Serialise a model's content (estimators, arrays, plain data) as a skops artifact.

    Parameters
    ----------
    content : dict
        JSON-like data and estimators; a ``format`` key is added.
    """
    skops_io = import_skops_io()

    return bytes(skops_io.dumps({"format": ARTIFACT_FORMAT, **content}))


def loads_artifact(data: bytes) -> dict[str, Any]:
    """Load an artifact written by :func:`dumps_artifact`, refusing untrusted types.

    Raises
    ------
    ConfigurationError
        The bytes are not a skops artifact, name a type outside
        :data:`TRUSTED_PACKAGES` (or a function), or are not a touchbench model.
    MissingExtraError
        The model is made of a library of an extra that is not installed.
    """
    skops_io = import_skops_io()

    if not zipfile.is_zipfile(io.BytesIO(data)):
        raise ConfigurationError(
            "the stored model is not a skops artifact (an old pickle, or foreign bytes); "
            "touchbench only loads artifacts that cannot run code: train the model again"
        )
    try:
        data = _renamed_modules(data)
        named = skops_io.get_untrusted_types(data=data)
    except Exception as exc:
        raise ConfigurationError(f"the stored model cannot be read: {exc}") from None
    optional = {name.split(".", 1)[0] for name in named} & EXTRA_OF.keys()
    require(sorted(optional), "the stored model")
    refused = [name for name in named if not is_trusted_type(name)]
    if refused:
        shown = ", ".join(refused[:3]) + (f" (+{len(refused) - 3})" if len(refused) > 3 else "")
        raise ConfigurationError(
            f"the stored model names types touchbench does not trust ({shown}); refusing to load it"
        )
    try:
        content = skops_io.loads(data, trusted=named)
    except Exception as exc:
        raise ConfigurationError(f"the stored model cannot be loaded: {exc}") from None
    if not isinstance(content, dict) or content.get("format") != ARTIFACT_FORMAT:
        raise ConfigurationError("the stored bytes are not a touchbench model")
    return content


def is_trusted_type(name: str) -> bool:
    """Whether ``name`` (``module.Class``) is a class of a trusted package.

    Only the module is imported (trusted packages' modules import without side effects);
    the attribute must be a class, so no function can be named and called.
    """
    if name in TRUSTED_NAMES:
        return True
    module_name, _, attribute = name.rpartition(".")
    if not any(_within(module_name, package) for package in TRUSTED_PACKAGES):
        return False
    try:
        target = getattr(importlib.import_module(module_name), attribute)
    except (ImportError, AttributeError, ValueError):
        return False
    if not isinstance(target, type):
        return False
    import numpy

    refused = [numpy.memmap, *(_numpy_type(name) for name in REFUSED_TYPES)]
    return not any(issubclass(target, kind) for kind in refused if kind is not None)


def _within(module_name: str, package: str) -> bool:
    return module_name == package or module_name.startswith(package + ".")


def _renamed_modules(data: bytes) -> bytes:
    """``data`` with the modules of :data:`MOVED_PACKAGES` named as they are now (an
    artifact written before the move), else ``data`` itself."""
    with zipfile.ZipFile(io.BytesIO(data)) as archive:
        text = archive.read("schema.json")
        if not any(f'"{old}.'.encode() in text for old in MOVED_PACKAGES):
            return data
        schema = json.loads(text)
        if not _rename(schema):
            return data
        renamed = io.BytesIO()
        with zipfile.ZipFile(renamed, "w", compression=zipfile.ZIP_DEFLATED) as copy:
            for member in archive.infolist():
                if member.filename == "schema.json":
                    copy.writestr(member, json.dumps(schema))
                else:
                    copy.writestr(member, archive.read(member))
    return renamed.getvalue()


def _rename(node: Any) -> bool:
    """Rename the moved modules in a skops schema in place; whether any was."""
    renamed = False
    if isinstance(node, dict):
        for key, value in node.items():
            if key in ("__module__", "module_path") and isinstance(value, str):
                top, dot, rest = value.partition(".")
                if top in MOVED_PACKAGES:
                    node[key] = MOVED_PACKAGES[top] + dot + rest
                    renamed = True
            else:
                renamed = _rename(value) or renamed
    elif isinstance(node, list):
        for item in node:
            renamed = _rename(item) or renamed
    return renamed


def _numpy_type(name: str) -> type | None:
    module_name, _, attribute = name.rpartition(".")
    try:
        found = getattr(importlib.import_module(module_name), attribute)
    except (ImportError, AttributeError):
        return None
    return found if isinstance(found, type) else None
