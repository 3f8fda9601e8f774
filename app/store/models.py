"""Trained models in the store: the artifact's bytes with their sha256 and format, the schema
the model expects, the classifier and its parameters, the data set and run it came from,
and how that data set was extracted from recordings.

Artifacts live in a table of their own (``model_artifacts``), so listings and the version
check of every served prediction never read one; :func:`load_artifact` reads one, and
only a format that cannot run code when loaded (``skops``) is handed out.

Models stored under one name are its versions 1, 2, ... (training again under a name adds
one).  A reference to a model is its id, ``NAME`` (the newest version), ``NAME@VERSION``,
``NAME@latest`` or ``NAME@ALIAS`` (an alias such as ``champion`` points at one version;
:func:`set_alias` moves it and keeps its history, :func:`rollback_alias` steps back).
"""

from __future__ import annotations

import hashlib
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from datetime import datetime
from typing import Any

from sqlalchemy import and_, bindparam, delete, func, select, update
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from touchbench.app.errors import AppError, ConflictError, FieldError, NotFoundError
from touchbench.app.schemas.listing import Page
from touchbench.app.schemas.models import AliasMoved, ModelSchema
from touchbench.app.schemas.names import check_alias, check_name
from touchbench.app.schemas.references import (
    SEPARATOR,
    ModelRef,
    parse_model_ref,
    version_label,
)
from touchbench.app.store.database import Store
from touchbench.app.store.naming import find_row, may_be_name, shorten
from touchbench.app.store.paging import count_rows, paged
from touchbench.app.store.tables import (
    MODEL_VERSION_KEY,
    DatasetRow,
    ModelAliasEventRow,
    ModelAliasRow,
    ModelArtifactRow,
    ModelRow,
    utcnow,
)

#: The only artifact format that is loaded (see :mod:`benchmark.artifacts`).
SAFE_FORMAT = "skops"
#: The alias ``promote`` sets and ``rollback`` steps back.
CHAMPION = "champion"
#: Attempts at a free version number when other processes store versions of the same name.
VERSION_ATTEMPTS = 20


@dataclass(frozen=True)
class ModelInfo:
    id: int
    name: str
    classifier: str
    params: dict[str, Any]
    targets: list[str]
    dataset_id: int | None
    dataset_name: str | None
    run_id: int | None
    sha256: str
    size_bytes: int
    created_at: datetime
    schema: dict[str, Any]
    format: str = SAFE_FORMAT
    extraction: dict[str, Any] | None = None
    version: int = 1
    aliases: tuple[str, ...] = ()

    @property
    def label(self) -> str:
        """``NAME@VERSION``: the one version this is, as answers name it."""
        return version_label(self.name, self.version)

    @property
    def feature_names(self) -> list[str]:
        targets = set(self.schema.get("target_indices", ()))
        return [
            attribute["name"]
            for i, attribute in enumerate(self.schema.get("attributes", ()))
            if i not in targets
        ]

    def to_schema(self) -> ModelSchema:
        return ModelSchema(
            id=self.id,
            name=self.name,
            version=self.version,
            aliases=list(self.aliases),
            classifier=self.classifier,
            targets=self.targets,
            dataset=self.dataset_name,
            dataset_id=self.dataset_id,
            run_id=self.run_id,
            sha256=self.sha256,
            size_bytes=self.size_bytes,
            format=self.format,
            created_at=self.created_at,
            features=self.feature_names,
            extraction=self.extraction,
        )

    def to_json(self) -> dict[str, Any]:
        return self.to_schema().to_json()


def save_model(
    store: Store,
    *,
    classifier: str,
    params: dict[str, Any],
    schema: dict[str, Any],
    targets: Sequence[str],
    artifact: bytes,
    dataset_id: int | None = None,
    run_id: int | None = None,
    name: str | None = None,
) -> ModelInfo:
    """Store a model's artifact as the next version of ``name`` (default
    ``DATASET-CLASSIFIER``: training the same classifier on the same data set again is a
    new version of that model, not another model).

    The data set's extraction recipe (if it was extracted from recordings) is copied to
    the model, so that live prediction extracts features as training did.  Processes that
    store versions of one name at once each get their own: the store's unique ``(name,
    version)`` refuses a taken one, and the next free number is tried.
    """
    if name is not None:
        check_model_name(name)
    for _attempt in range(VERSION_ATTEMPTS):
        try:
            with store.session() as session:
                dataset = session.get(DatasetRow, dataset_id) if dataset_id is not None else None
                chosen = name if name is not None else default_model_name(dataset, classifier)
                row = ModelRow(
                    name=chosen,
                    version=_next_version(session, chosen),
                    dataset_id=dataset_id,
                    run_id=run_id,
                    classifier=classifier,
                    params=params,
                    schema=schema,
                    targets=list(targets),
                    sha256=hashlib.sha256(artifact).hexdigest(),
                    size_bytes=len(artifact),
                    format=SAFE_FORMAT,
                    extraction=dataset.extraction if dataset is not None else None,
                )
                session.add(row)
                session.flush()  # waits for a concurrent insert of the same version to end
                session.add(ModelArtifactRow(model_id=row.id, artifact=artifact))
                return _info(session, row)
        except IntegrityError as error:
            if not _version_taken(error):
                raise
            # another process stored this version meanwhile: take the next one
    raise ConflictError(
        f"could not find a free version of model '{shorten(str(name))}' after "
        f"{VERSION_ATTEMPTS} attempts (busy store); try again"
    )


def default_model_name(dataset: DatasetRow | None, classifier: str) -> str:
    """``DATASET-CLASSIFIER`` (``@`` folded to ``_``: it would read as a version)."""
    base = f"{dataset.name if dataset else 'model'}-{classifier}".replace(SEPARATOR, "_")
    return base[:200]


def _next_version(session: Session, name: str) -> int:
    top = session.scalar(select(func.max(ModelRow.version)).where(ModelRow.name == name))
    return int(top or 0) + 1


def _version_taken(error: IntegrityError) -> bool:
    """Whether ``error`` is the unique ``(name, version)`` refusing a taken version."""
    text = str(error.orig)
    return MODEL_VERSION_KEY in text or "models.version" in text


def check_model_name(name: str) -> None:
    """Refuse names that cannot be told from ids or versions, or do not print
    (:func:`app.schemas.names.check_name`).

    Raises
    ------
    FieldError
        For the request's ``name``, saying which rule the name breaks.
    """
    try:
        check_name(name, kind="model")
    except AppError as error:
        raise FieldError("name", str(error)) from None


def list_models(store: Store, *, page: Page | None = None) -> list[ModelInfo]:
    """Every model version (those of ``page``), oldest first, with their aliases, without
    reading any artifact."""
    with store.session() as session:
        rows = list(session.scalars(paged(select(ModelRow).order_by(ModelRow.id), page)))
        names = _dataset_names(session, rows)
        aliases = _aliases(session, {row.name for row in rows})
        return [_info(session, row, names, aliases) for row in rows]


def count_models(store: Store) -> int:
    return count_rows(store, ModelRow)


def get_model(store: Store, ref: str | int) -> ModelInfo:
    """A model's description (its artifact is not read)."""
    with store.session() as session:
        return _info(session, _row(session, ref))


def model_version(store: Store, ref: str | int) -> tuple[int, str, str]:
    """The id, artifact sha256 and ``NAME@VERSION`` of the model ``ref`` names now: one
    or two indexed queries on the driver's cursor.

    The service's model cache asks this on every prediction to know whether the model it
    holds is still the stored one (and the one an alias points at), and a live session
    to follow ``NAME@champion``.

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
        elif parsed.alias is not None:
            found = store.first_row(_VERSION_BY_ALIAS, ref=parsed.name, alias=parsed.alias)
        if found is None:
            found = store.first_row(_VERSION_BY_NAME, ref=text)
    if found is None and parsed.id is not None:
        found = store.first_row(_VERSION_BY_ID, ref=parsed.id)
    if found is None:
        get_model(store, text)  # raises NotFoundError naming the known models
        raise AssertionError("get_model found a model the version query did not")
    return int(found[0]), str(found[1]), version_label(found[2], found[3])


_VERSION = select(ModelRow.id, ModelRow.sha256, ModelRow.name, ModelRow.version)
_VERSION_BY_NAME = (
    _VERSION.where(ModelRow.name == bindparam("ref")).order_by(ModelRow.version.desc()).limit(1)
)
_VERSION_BY_NUMBER = _VERSION.where(
    ModelRow.name == bindparam("ref"), ModelRow.version == bindparam("number")
)
_VERSION_BY_ALIAS = _VERSION.join(
    ModelAliasRow,
    and_(ModelAliasRow.name == ModelRow.name, ModelAliasRow.version == ModelRow.version),
).where(ModelAliasRow.name == bindparam("ref"), ModelAliasRow.alias == bindparam("alias"))
_VERSION_BY_ID = _VERSION.where(ModelRow.id == bindparam("ref"))


def load_artifact(store: Store, ref: str | int) -> tuple[ModelInfo, bytes]:
    """A model's description and artifact bytes (check them with the sha256 before use).

    Raises
    ------
    AppError
        The artifact is in a format that could run code when loaded (models stored by
        touchbench before 0.2 were pickles).
    """
    with store.session() as session:
        row = _row(session, ref)
        info = _info(session, row)
        if row.format != SAFE_FORMAT:
            raise AppError(
                f"model '{row.name}' is stored as a {row.format}, a format that can run code "
                "when loaded; train it again under another name"
            )
        artifact = session.get_one(ModelArtifactRow, row.id).artifact
        return info, bytes(artifact)


def delete_model(store: Store, ref: str | int) -> ModelInfo:
    """Delete the version ``ref`` names (``NAME``: the newest); aliases that pointed at it
    go with it (their history stays, and ``rollback`` skips versions that are gone)."""
    with store.session() as session:
        row = _row(session, ref)
        info = _info(session, row)
        session.execute(
            delete(ModelAliasRow).where(
                ModelAliasRow.name == row.name, ModelAliasRow.version == row.version
            )
        )
        session.execute(delete(ModelRow).where(ModelRow.id == row.id))
        return info


def rename_model(store: Store, ref: str | int, new_name: str) -> ModelInfo:
    """Give every version of the model ``ref`` names another name, with its aliases and
    their history; returns the version ``ref`` named.

    Raises
    ------
    ConflictError
        Another model has the name.
    """
    check_model_name(new_name)
    try:
        with store.session() as session:
            row = _row(session, ref)
            old, version = row.name, row.version
            if new_name != old:
                if session.scalars(select(ModelRow.id).where(ModelRow.name == new_name)).first():
                    raise ConflictError(_taken(new_name))
                for table in (ModelRow, ModelAliasRow, ModelAliasEventRow):
                    session.execute(update(table).where(table.name == old).values(name=new_name))
    except IntegrityError:
        raise ConflictError(_taken(new_name)) from None
    return get_model(store, f"{new_name}@{version}")


def _taken(name: str) -> str:
    return f"a model named '{shorten(name)}' already exists; choose another name"


@dataclass(frozen=True)
class AliasMove:
    """An alias set or stepped back: the version it points at now, and before (None: it
    pointed at none)."""

    alias: str
    model: ModelInfo
    previous: int | None

    def to_schema(self) -> AliasMoved:
        return AliasMoved(
            alias=self.alias,
            model=self.model.label,
            version=self.model.version,
            previous=self.previous,
        )

    def to_json(self) -> dict[str, Any]:
        return self.to_schema().to_json()


def set_alias(store: Store, ref: str | int, alias: str) -> AliasMove:
    """Point ``NAME@alias`` at the version ``ref`` names, and note it in the alias's history.

    Raises
    ------
    FieldError
        An invalid alias (``alias``).
    NotFoundError
        No such model or version.
    """
    try:
        check_alias(alias)
    except AppError as error:
        raise FieldError("alias", str(error)) from None
    for _attempt in range(VERSION_ATTEMPTS):
        try:
            with store.session() as session:
                row = _row(session, ref)
                current = _alias_row(session, row.name, alias)
                previous = None if current is None else current.version
                if current is None:
                    session.add(ModelAliasRow(name=row.name, alias=alias, version=row.version))
                else:
                    current.version = row.version
                    current.set_at = utcnow()
                session.add(ModelAliasEventRow(name=row.name, alias=alias, version=row.version))
                session.flush()  # a concurrent first setting of the alias: try again
                return AliasMove(alias, _info(session, row), previous)
        except IntegrityError:
            continue
    raise ConflictError(f"could not set alias '{alias}' (busy store); try again")


def rollback_alias(store: Store, ref: str | int, alias: str = CHAMPION) -> AliasMove:
    """Point ``NAME@alias`` back at the version it pointed at before its last move (a
    second rollback goes one step further back); versions deleted since are skipped.

    Raises
    ------
    NotFoundError
        No such model.
    ConflictError
        The alias points at nothing, or at the only version it ever pointed at.
    """
    with store.session() as session:
        name = _row(session, ref).name
        current = _alias_row(session, name, alias)
        if current is None:
            raise ConflictError(
                f"model '{shorten(name)}' has no alias '{alias}' to roll back (set it with "
                f"`promote` or `alias` first)"
            )
        for step in _alias_steps(session, name, alias):
            target = (
                _version_row(session, name, step.version)
                if step.version != current.version
                else None
            )
            if target is not None:
                previous, current.version, current.set_at = current.version, step.version, utcnow()
                return AliasMove(alias, _info(session, target), previous)
            step.undone = True  # the move being undone, or a version deleted since
        raise ConflictError(
            f"'{shorten(name)}@{alias}' has pointed at no other version that still exists "
            f"(now version {current.version}): nothing to roll back to"
        )


def delete_alias(store: Store, ref: str | int, alias: str) -> AliasMove:
    """Remove ``NAME@alias``; returns the version it pointed at (``model``, and
    ``previous``).  Its history is marked undone, so that the alias set again later starts
    afresh (``rollback`` does not step back past its deletion).

    A ``ref`` that names one version (an id, ``NAME@VERSION``) deletes the alias only while
    it points at that version: an alias another client moved since is not removed unseen.

    Raises
    ------
    FieldError
        An invalid alias (``alias``).
    NotFoundError
        No such model, or the model has no such alias.
    ConflictError
        ``ref`` names a version the alias does not point at.
    """
    try:
        check_alias(alias)
    except AppError as error:
        raise FieldError("alias", str(error)) from None
    with store.session() as session:
        row = _row(session, ref)
        current = _alias_row(session, row.name, alias)
        if current is None:
            known = _aliases(session, {row.name})
            names = sorted(a for aliases in known.values() for a in aliases)
            raise NotFoundError(
                f"model '{shorten(row.name)}' has no alias '{alias}' (aliases: "
                f"{', '.join(names) or 'none'})"
            )
        if parse_model_ref(ref).pinned and current.version != row.version:
            raise ConflictError(
                f"'{shorten(row.name)}@{alias}' points at version {current.version}, not "
                f"{row.version}: not deleted (name the model without a version to delete it "
                "whatever it points at)"
            )
        target = _version_row(session, row.name, current.version)
        assert target is not None  # deleting a version deletes the aliases on it
        session.execute(
            update(ModelAliasEventRow)
            .where(ModelAliasEventRow.name == row.name, ModelAliasEventRow.alias == alias)
            .values(undone=True)
        )
        session.delete(current)
        return AliasMove(alias, _info(session, target), current.version)


#: History steps read per query by :func:`_alias_steps`.
ALIAS_STEPS_PAGE = 16


def _alias_steps(session: Session, name: str, alias: str) -> Iterator[ModelAliasEventRow]:
    """The alias's moves not undone, newest first, read a page at a time: a rollback
    usually stops at the second, and an alias moved 20,000 times took 0.9 s to read whole."""
    before: int | None = None
    while True:
        query = select(ModelAliasEventRow).where(
            ModelAliasEventRow.name == name,
            ModelAliasEventRow.alias == alias,
            ModelAliasEventRow.undone.is_(False),
        )
        if before is not None:
            query = query.where(ModelAliasEventRow.id < before)
        page = session.scalars(
            query.order_by(ModelAliasEventRow.id.desc()).limit(ALIAS_STEPS_PAGE)
        ).all()
        yield from page
        if len(page) < ALIAS_STEPS_PAGE:
            return
        before = page[-1].id


def _alias_row(session: Session, name: str, alias: str) -> ModelAliasRow | None:
    return session.get(ModelAliasRow, (name, alias))


def _version_row(session: Session, name: str, version: int) -> ModelRow | None:
    return session.scalars(
        select(ModelRow).where(ModelRow.name == name, ModelRow.version == version)
    ).first()


def _row(session: Session, ref: str | int) -> ModelRow:
    """The model version ``ref`` names: a name (its newest version), an id, or
    ``NAME@VERSION``, ``NAME@latest``, ``NAME@ALIAS``.

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
                row = _newest(session, parsed.text)
                if row is None:
                    raise
                return row
        row = _newest(session, parsed.text)
        if row is not None:
            return row
    return find_row(
        session, ModelRow, parsed.text, kind="model", hint="none yet; training makes one"
    )


def _newest(session: Session, name: str) -> ModelRow | None:
    return session.scalars(
        select(ModelRow).where(ModelRow.name == name).order_by(ModelRow.version.desc())
    ).first()


def _version_of(session: Session, ref: ModelRef) -> ModelRow:
    """The version of ``NAME@VERSION``, ``NAME@latest`` or ``NAME@ALIAS``."""
    name, suffix = ref.name, str(ref.suffix)
    versions = list(
        session.scalars(
            select(ModelRow).where(ModelRow.name == name).order_by(ModelRow.version.desc())
        )
    )
    if not versions:
        find_row(session, ModelRow, name, kind="model", hint="none yet; training makes one")
        raise AssertionError("find_row found a name the query did not")
    if ref.kind == "latest":
        return versions[0]
    if ref.kind == "version":
        for row in versions:
            if row.version == ref.version:
                return row
        known = ", ".join(str(row.version) for row in reversed(versions[:20]))
        raise NotFoundError(
            f"model '{shorten(name)}' has no version {suffix[:12]} (versions: {known})"
        )
    alias = _alias_row(session, name, suffix) if may_be_name(suffix) else None
    if alias is not None:
        for row in versions:
            if row.version == alias.version:
                return row
    known = ", ".join(
        f"{a}->{v}"
        for a, v in session.execute(
            select(ModelAliasRow.alias, ModelAliasRow.version).where(ModelAliasRow.name == name)
        ).all()
    )
    raise NotFoundError(
        f"model '{shorten(name)}' has no alias '{shorten(suffix)}' (aliases: "
        f"{known or 'none; `promote NAME@VERSION` sets champion'})"
    )


def _dataset_names(session: Session, rows: Sequence[ModelRow]) -> dict[int, str]:
    ids = {row.dataset_id for row in rows if row.dataset_id is not None}
    if not ids:
        return {}
    return dict(
        session.execute(select(DatasetRow.id, DatasetRow.name).where(DatasetRow.id.in_(ids))).all()
    )


def _aliases(session: Session, names: set[str]) -> dict[tuple[str, int], tuple[str, ...]]:
    """(name, version) -> the aliases that point at it, sorted."""
    if not names:
        return {}
    found: dict[tuple[str, int], list[str]] = {}
    rows = session.execute(
        select(ModelAliasRow.name, ModelAliasRow.version, ModelAliasRow.alias)
        .where(ModelAliasRow.name.in_(names))
        .order_by(ModelAliasRow.alias)
    )
    for name, version, alias in rows:
        found.setdefault((name, version), []).append(alias)
    return {key: tuple(aliases) for key, aliases in found.items()}


def _info(
    session: Session,
    row: ModelRow,
    names: dict[int, str] | None = None,
    aliases: dict[tuple[str, int], tuple[str, ...]] | None = None,
) -> ModelInfo:
    if names is None:
        names = _dataset_names(session, [row])
    if aliases is None:
        aliases = _aliases(session, {row.name})
    return ModelInfo(
        id=row.id,
        name=row.name,
        version=row.version,
        aliases=aliases.get((row.name, row.version), ()),
        classifier=row.classifier,
        params=dict(row.params),
        targets=list(row.targets),
        dataset_id=row.dataset_id,
        dataset_name=names.get(row.dataset_id) if row.dataset_id is not None else None,
        run_id=row.run_id,
        sha256=row.sha256,
        size_bytes=row.size_bytes,
        created_at=row.created_at,
        schema=dict(row.schema),
        format=row.format,
        extraction=row.extraction,
    )
