"""How users refer to stored rows: a numeric id, and the grammar of a model reference, once.

A model reference is one of

- ``NAME``: the newest version of the model ``NAME``;
- ``NAME@3``: its version 3 (``NAME@VERSION``, the one version it is for good);
- ``NAME@latest``: the newest version, whatever the aliases say;
- ``NAME@champion``: the version the alias ``champion`` points at now (``NAME@ALIAS``);
- a numeric id (``17``): the one version with that id, for good.

:func:`parse_model_ref` reads it into a :class:`ModelRef`; the store resolves that against
its rows, and everything else (the service's cache, live sessions, the CLI) asks the value
rather than splitting the text itself.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

#: The largest id a row can have (the columns are 32-bit integers on PostgreSQL).
MAX_ROW_ID = 2**31 - 1
#: ``NAME@latest`` is the newest version, whatever the aliases say.
LATEST = "latest"
#: What separates a model's name from the version or alias of ``NAME@VERSION``.
SEPARATOR = "@"


def is_decimal(text: str) -> bool:
    """Whether ``text`` is ASCII digits only (``str.isdigit`` also takes ``"²"``, which
    ``int`` refuses, and ``int`` takes other scripts' digits, which no id is written in)."""
    return text.isascii() and text.isdigit()


def is_row_id(text: str) -> bool:
    """Whether ``text`` can be the id of a row (so that looking it up cannot fail)."""
    return is_decimal(text) and len(text) <= 10 and 0 < int(text) <= MAX_ROW_ID


#: What the part after ``@`` names: a version number, the newest version, or an alias.
SuffixKind = Literal["version", "latest", "alias"]


@dataclass(frozen=True)
class ModelRef:
    """A model reference as :func:`parse_model_ref` reads it.

    Attributes
    ----------
    text : str
        The reference as given (a name stored with ``@`` in it before names refused one is
        found by this whole text).
    name : str
        The model's name: the text before the last ``@``, or the whole text without one.
    suffix : str or None
        The text after the last ``@``; None without one.
    kind : {"version", "latest", "alias"} or None
        What ``suffix`` names; None without a suffix (the newest version).
    version : int or None
        The version number of ``NAME@VERSION``; None otherwise, and for a number that no
        version can have (``NAME@0``, eleven digits), which names no version.
    """

    text: str
    name: str
    suffix: str | None = None
    kind: SuffixKind | None = None
    version: int | None = None

    @property
    def id(self) -> int | None:
        """The row id the whole reference can be, else None."""
        return int(self.text) if is_row_id(self.text) else None

    @property
    def alias(self) -> str | None:
        """The alias of ``NAME@ALIAS``, else None."""
        return self.suffix if self.kind == "alias" else None

    @property
    def newest(self) -> bool:
        """Whether the reference names its model's newest version (``NAME``,
        ``NAME@latest``), if it is not an id."""
        return self.kind in (None, "latest")

    @property
    def pinned(self) -> bool:
        """Whether the reference names one version for good (an id, ``NAME@VERSION``),
        rather than whichever version a name's newest or an alias is now."""
        return self.id is not None or self.kind == "version"


def parse_model_ref(ref: str | int | ModelRef) -> ModelRef:
    """Read a model reference (see the module's description); never fails: whether the
    model exists is the store's question."""
    if isinstance(ref, ModelRef):
        return ref
    text = str(ref)
    name, separator, suffix = text.rpartition(SEPARATOR)
    if not separator:
        return ModelRef(text=text, name=text)
    if is_decimal(suffix):
        number = int(suffix) if is_row_id(suffix) else None
        return ModelRef(text=text, name=name, suffix=suffix, kind="version", version=number)
    kind: SuffixKind = "latest" if suffix == LATEST else "alias"
    return ModelRef(text=text, name=name, suffix=suffix, kind=kind)


def version_label(name: str, version: int) -> str:
    """``NAME@VERSION``: how answers name one version of a model."""
    return f"{name}{SEPARATOR}{version}"
