"""Model references resolved against the registry: the version ``NAME``, ``NAME@VERSION``,
``NAME@latest``, ``NAME@ALIAS`` or an id names now (read by
:func:`app.schemas.references.parse_model_ref`), as a row of a session
(:func:`version_row`), or in one indexed query for the model cache (:func:`model_version`).

A name with ``@`` in it that names no version is looked up whole, so that a model stored
with ``@`` in its name before names refused it is still found.
"""

from __future__ import annotations

from typing import NamedTuple

from sqlalchemy import and_, bindparam, exists, func, select
from sqlalchemy.orm import Session

from touchbench.app.errors import NotFoundError
from touchbench.app.schemas.references import ModelRef, parse_model_ref, version_label
from touchbench.app.store.database import Store
from touchbench.app.store.naming import may_be_name, shorten
from touchbench.app.store.tables import (
    ModelAliasRow,
    ModelExportRow,
    ModelRow,
    RegisteredModelRow,
)

#: The format of the twin that predictions may run (``engine``), and the version query reads.
TWIN_FORMAT = "onnx"
#: Names listed in a "no such model" message.
_NAMES_SHOWN = 10
#: Versions listed in a "no such version" message (the newest).
_VERSIONS_SHOWN = 20


class ModelVersion(NamedTuple):
    """What a reference names now, in one indexed query (:func:`model_version`): the
    version's id, its artifact's sha256, ``NAME@VERSION``, and its ONNX twin's sha256 (None
    without one)."""

    id: int
    sha256: str
    label: str
    twin: str | None = None


def model_version(store: Store, ref: str | int) -> ModelVersion:
    """The id, artifact sha256, ``NAME@VERSION`` and ONNX twin's sha256 of the model ``ref``
    names now: one or two indexed queries on the driver's cursor.

    The model cache (:mod:`app.services.model_cache`) asks this to know whether a model it
    holds is still the one ``ref`` names (a version deleted, an alias moved, a twin made).

    Raises
    ------
    NotFoundError
        As :func:`get_model` does.
    """
    parsed = parse_model_ref(ref)
    text, found = parsed.text, None
    if may_be_name(text):
        # one query for NAME@champion; a name stored with '@' next
        if parsed.version is not None:
            found = store.first_row(_VERSION_BY_NUMBER, ref=parsed.name, number=parsed.version)
        elif parsed.kind == "latest":
            found = store.first_row(_VERSION_BY_NAME, ref=parsed.name)
        elif parsed.alias is not None and may_be_name(parsed.alias):
            found = store.first_row(_VERSION_BY_ALIAS, ref=parsed.name, alias=parsed.alias)
        if found is None:
            found = store.first_row(_VERSION_BY_NAME, ref=text)
    if found is None and parsed.id is not None:
        found = store.first_row(_VERSION_BY_ID, ref=parsed.id)
    if found is None:
        with store.session() as session:
            version_row(session, text)  # raises NotFoundError naming the known models
        raise AssertionError("version_row found a model the version query did not")
    model_id, sha256, name, version, twin = found
    return ModelVersion(int(model_id), str(sha256), version_label(name, version), twin)


_VERSION = (
    select(
        ModelRow.id,
        ModelRow.sha256,
        RegisteredModelRow.name,
        ModelRow.version,
        ModelExportRow.sha256,
    )
    .join(RegisteredModelRow, RegisteredModelRow.id == ModelRow.registered_model_id)
    .outerjoin(
        ModelExportRow,
        and_(ModelExportRow.model_id == ModelRow.id, ModelExportRow.format == TWIN_FORMAT),
    )
)
_VERSION_BY_NAME = (
    _VERSION.where(RegisteredModelRow.name == bindparam("ref"))
    .order_by(ModelRow.version.desc())
    .limit(1)
)
_VERSION_BY_NUMBER = _VERSION.where(
    RegisteredModelRow.name == bindparam("ref"), ModelRow.version == bindparam("number")
)
_VERSION_BY_ALIAS = _VERSION.join(
    ModelAliasRow,
    and_(
        ModelAliasRow.registered_model_id == ModelRow.registered_model_id,
        ModelAliasRow.version == ModelRow.version,
    ),
).where(RegisteredModelRow.name == bindparam("ref"), ModelAliasRow.alias == bindparam("alias"))
_VERSION_BY_ID = _VERSION.where(ModelRow.id == bindparam("ref"))


def version_row(session: Session, ref: str | int) -> ModelRow:
    """The model version ``ref`` names (:func:`app.schemas.references.parse_model_ref`): a
    name (its newest version), an id, or ``NAME@VERSION``, ``NAME@latest``, ``NAME@ALIAS``.

    A name with ``@`` in it that names no version is looked up whole, so that a model
    stored with ``@`` in its name before names refused it is still found.

    Raises
    ------
    NotFoundError
        Naming the known models, or the known versions and aliases of ``NAME``.
    """
    parsed = parse_model_ref(ref)
    if may_be_name(parsed.text):
        if parsed.suffix is not None:
            try:
                return _version_of(session, parsed)
            except NotFoundError:
                if registered(session, parsed.text) is None:
                    raise
        parent = registered(session, parsed.text)
        if parent is not None and (parsed.id is None or _has_versions(session, parent.id)):
            return _newest(session, parent)
    if parsed.id is not None:
        row = session.get(ModelRow, parsed.id)
        if row is not None:
            return row
    raise _unknown(session, parsed.text)


def registered(session: Session, name: str) -> RegisteredModelRow | None:
    """The registered model called ``name``, whether or not it has versions left."""
    return session.scalars(
        select(RegisteredModelRow).where(RegisteredModelRow.name == name)
    ).first()


def _has_versions(session: Session, parent: int) -> bool:
    return bool(session.scalar(select(exists().where(ModelRow.registered_model_id == parent))))


def _newest(session: Session, parent: RegisteredModelRow) -> ModelRow:
    """The newest version of ``parent``.

    Raises
    ------
    NotFoundError
        Every version of it was deleted.
    """
    row = session.scalars(
        select(ModelRow)
        .where(ModelRow.registered_model_id == parent.id)
        .order_by(ModelRow.version.desc())
        .limit(1)
    ).first()
    if row is None:
        raise NotFoundError(
            f"model '{shorten(parent.name)}' has no versions left (versions up to "
            f"{parent.last_version} were deleted; training under its name makes version "
            f"{parent.last_version + 1})"
        )
    return row


def _version_of(session: Session, ref: ModelRef) -> ModelRow:
    """The version of ``NAME@VERSION``, ``NAME@latest`` or ``NAME@ALIAS``."""
    parent = registered(session, ref.name)
    if parent is None:
        raise _unknown(session, ref.name)
    if ref.kind == "latest":
        return _newest(session, parent)
    suffix = str(ref.suffix)
    if ref.kind == "version":
        row = None
        if ref.version is not None:
            row = session.scalars(
                select(ModelRow).where(
                    ModelRow.registered_model_id == parent.id, ModelRow.version == ref.version
                )
            ).first()
        if row is not None:
            return row
        newest = session.scalars(
            select(ModelRow.version)
            .where(ModelRow.registered_model_id == parent.id)
            .order_by(ModelRow.version.desc())
            .limit(_VERSIONS_SHOWN)
        ).all()
        known = ", ".join(str(version) for version in reversed(newest)) or "none left"
        raise NotFoundError(
            f"model '{shorten(parent.name)}' has no version {suffix[:12]} (versions: {known})"
        )
    alias = session.get(ModelAliasRow, (parent.id, suffix)) if may_be_name(suffix) else None
    if alias is not None:
        return session.scalars(
            select(ModelRow).where(
                ModelRow.registered_model_id == parent.id, ModelRow.version == alias.version
            )
        ).one()  # an alias goes with its version (a foreign key)
    known = ", ".join(
        f"{a}->{v}"
        for a, v in session.execute(
            select(ModelAliasRow.alias, ModelAliasRow.version).where(
                ModelAliasRow.registered_model_id == parent.id
            )
        ).all()
    )
    raise NotFoundError(
        f"model '{shorten(parent.name)}' has no alias '{shorten(suffix)}' (aliases: "
        f"{known or 'none; `promote NAME@VERSION` sets champion'})"
    )


def _unknown(session: Session, text: str) -> NotFoundError:
    """No model is ``text``: the error, naming the first models that have versions."""
    with_versions = exists().where(ModelRow.registered_model_id == RegisteredModelRow.id)
    names = session.scalars(
        select(RegisteredModelRow.name)
        .where(with_versions)
        .order_by(RegisteredModelRow.id)
        .limit(_NAMES_SHOWN)
    ).all()
    if names:
        known = ", ".join(shorten(name) for name in names)
        total = session.scalar(
            select(func.count()).select_from(RegisteredModelRow).where(with_versions)
        )
        if (total or 0) > len(names):
            known += f", ... ({total} in all)"
    else:
        known = "none yet; training makes one"
    return NotFoundError(f"no model '{shorten(text)}' (models: {known})")
