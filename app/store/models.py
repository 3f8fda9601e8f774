"""Trained models in the store, as a registry: a registered model per name
(``registered_models``), its versions (``models``: the artifact's sha256 and format, the
schema the model expects, the classifier and its parameters, the data set and run it came
from, and how that data set was extracted from recordings).

Artifacts live in a table of their own (``model_artifacts``), so listings and the version
check of every served prediction never read one; :func:`load_artifact` reads one, and
only a format that cannot run code when loaded (``skops``) is handed out.

Models stored under one name are its versions 1, 2, ... (training again under a name adds
one).  A number is taken from the registered model's counter, which only grows, and ids
are never given twice either: ``NAME@VERSION`` and an id name one model for good, even
after it is deleted.  A reference to a model is read by
:func:`app.schemas.references.parse_model_ref` (an id, ``NAME``: the newest version,
``NAME@VERSION``, ``NAME@latest``, ``NAME@ALIAS``) and resolved here; aliases are
:mod:`app.store.aliases`' business.
"""

from __future__ import annotations

import hashlib
from collections.abc import Collection, Sequence
from dataclasses import dataclass
from datetime import datetime
from typing import Any, NamedTuple

from sqlalchemy import and_, bindparam, delete, exists, func, select, update
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from touchbench.app.errors import AppError, ConflictError, FieldError, NotFoundError
from touchbench.app.schemas.listing import Page
from touchbench.app.schemas.models import ModelSchema, TwinSchema
from touchbench.app.schemas.names import check_name
from touchbench.app.schemas.references import (
    SEPARATOR,
    ModelRef,
    parse_model_ref,
    version_label,
)
from touchbench.app.store.database import Store
from touchbench.app.store.naming import may_be_name, shorten
from touchbench.app.store.paging import count_rows, paged
from touchbench.app.store.tables import (
    DatasetRow,
    ModelAliasRow,
    ModelArtifactRow,
    ModelExportRow,
    ModelRow,
    RegisteredModelRow,
)

#: The only artifact format that is loaded (see :mod:`benchmark.artifacts`).
SAFE_FORMAT = "skops"
#: The format of the twin that predictions may run (``engine``), and the version query reads.
TWIN_FORMAT = "onnx"
#: Attempts at storing the first version of a name that other processes store at once.
VERSION_ATTEMPTS = 20
#: Names listed in a "no such model" message.
_NAMES_SHOWN = 10
#: Versions listed in a "no such version" message (the newest).
_VERSIONS_SHOWN = 20


@dataclass(frozen=True)
class TwinInfo:
    """A model's twin in another format (ONNX), as the store describes it (its bytes are
    not read); ``problem`` says why it could not be loaded, once a prediction tried."""

    format: str
    sha256: str
    size_bytes: int
    problem: str | None = None


class ModelVersion(NamedTuple):
    """What a reference names now, in one indexed query (:func:`model_version`): the
    version's id, its artifact's sha256, ``NAME@VERSION``, and its ONNX twin's sha256 (None
    without one)."""

    id: int
    sha256: str
    label: str
    twin: str | None = None


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
    twin: TwinInfo | None = None

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
            onnx=None
            if self.twin is None
            else TwinSchema(
                sha256=self.twin.sha256,
                size_bytes=self.twin.size_bytes,
                problem=self.twin.problem,
            ),
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
    the model, so that live prediction extracts features as training did.  The version's
    number is taken from the registered model's counter in the same statement that raises
    it, so processes storing versions of one name at once each get their own; two that
    register a new name at once are told apart by its unique key, and the second tries
    again.
    """
    if name is not None:
        check_model_name(name)
    for _attempt in range(VERSION_ATTEMPTS):
        try:
            with store.session() as session:
                dataset = session.get(DatasetRow, dataset_id) if dataset_id is not None else None
                chosen = name if name is not None else default_model_name(dataset, classifier)
                row = ModelRow(
                    registered_model_id=(parent := _register(session, chosen)),
                    version=take_version(session, parent),
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
                session.flush()
                session.add(ModelArtifactRow(model_id=row.id, artifact=artifact))
                return version_info(session, row)
        except IntegrityError as error:
            if "registered_models" not in str(error.orig):
                raise
            # another process registered the name meanwhile: its row is there now
    raise ConflictError(
        f"could not register model '{shorten(str(name))}' after {VERSION_ATTEMPTS} attempts "
        "(busy store); try again"
    )


def _register(session: Session, name: str) -> int:
    """The id of the registered model ``name``, registered now if it is new."""
    found = session.scalar(select(RegisteredModelRow.id).where(RegisteredModelRow.name == name))
    if found is not None:
        return int(found)
    parent = RegisteredModelRow(name=name, last_version=0)
    session.add(parent)
    session.flush()  # a concurrent registration of the name fails here
    return parent.id


def take_version(session: Session, parent: int) -> int:
    """Raise the registered model's counter and return it: the number of its next version
    (one UPDATE: another process raising it meanwhile waits for this transaction's end,
    then raises what this one left)."""
    raised = session.execute(
        update(RegisteredModelRow)
        .where(RegisteredModelRow.id == parent)
        .values(last_version=RegisteredModelRow.last_version + 1)
        .returning(RegisteredModelRow.last_version)
        .execution_options(synchronize_session=False)
    ).scalar_one()
    return int(raised)


def lock_registered(session: Session, parent: int) -> None:
    """Hold the registered model ``parent`` until the transaction ends (its row lock on
    PostgreSQL, the write lock on SQLite), as :func:`take_version` does, without changing
    it: every change to a model's versions and aliases takes it first, so that they happen
    one at a time, each on what the one before it left."""
    session.execute(
        update(RegisteredModelRow)
        .where(RegisteredModelRow.id == parent)
        .values(last_version=RegisteredModelRow.last_version)
        .execution_options(synchronize_session=False)
    )


def held_version(session: Session, ref: str | int) -> ModelRow:
    """The version ``ref`` names, read once its registered model is held
    (:func:`lock_registered`): what the changes before this one left.

    Raises
    ------
    NotFoundError
        ``ref`` names nothing now (another change deleted it meanwhile).
    ConflictError
        ``ref`` names another model now (renamed meanwhile).
    """
    row = version_row(session, ref)
    parent = row.registered_model_id
    lock_registered(session, parent)
    session.expire_all()  # rows read before the lock may have changed since
    row = version_row(session, ref)
    if row.registered_model_id != parent:
        raise ConflictError(
            f"'{shorten(str(ref))}' names another model than it did a moment ago (renamed "
            "meanwhile); try again"
        )
    return row


def default_model_name(dataset: DatasetRow | None, classifier: str) -> str:
    """``DATASET-CLASSIFIER`` (``@`` folded to ``_``: it would read as a version)."""
    base = f"{dataset.name if dataset else 'model'}-{classifier}".replace(SEPARATOR, "_")
    return base[:200]


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
        aliases = _aliases(session, {row.registered_model_id for row in rows})
        twins = _twins(session, [row.id for row in rows])
        return [version_info(session, row, names, aliases, twins) for row in rows]


def count_models(store: Store) -> int:
    """How many model versions the store holds."""
    return count_rows(store, ModelRow)


def get_model(store: Store, ref: str | int) -> ModelInfo:
    """A model's description (its artifact is not read)."""
    with store.session() as session:
        return version_info(session, version_row(session, ref))


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
        get_model(store, text)  # raises NotFoundError naming the known models
        raise AssertionError("get_model found a model the version query did not")
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


def load_artifact(store: Store, ref: str | int) -> tuple[ModelInfo, bytes]:
    """A model's description and artifact bytes (check them with the sha256 before use).

    Raises
    ------
    AppError
        The artifact is in a format that could run code when loaded (models stored by
        touchbench before 0.2 were pickles).
    """
    with store.session() as session:
        row = version_row(session, ref)
        info = version_info(session, row)
        if row.format != SAFE_FORMAT:
            raise AppError(
                f"model '{row.name}' is stored as a {row.format}, a format that can run code "
                "when loaded; train it again under another name"
            )
        artifact = session.get_one(ModelArtifactRow, row.id).artifact
        return info, bytes(artifact)


def delete_model(store: Store, ref: str | int) -> ModelInfo:
    """Delete the version ``ref`` names (``NAME``: the newest): one DELETE, its artifact,
    twins and the aliases that pointed at it going with it by cascade (their history
    stays, and ``rollback`` skips versions that are gone).  Its number and id are not given
    again."""
    with store.session() as session:
        row = held_version(session, ref)
        info = version_info(session, row)
        session.execute(delete(ModelRow).where(ModelRow.id == row.id))
        return info


def rename_model(store: Store, ref: str | int, new_name: str) -> ModelInfo:
    """Give the model ``ref`` names (every version, its aliases and their history) another
    name: one UPDATE of its registered model; returns the version ``ref`` named.

    Raises
    ------
    ConflictError
        Another model has the name, or had it (its numbers are not given again).
    """
    check_model_name(new_name)
    try:
        with store.session() as session:
            row = version_row(session, ref)
            version = row.version
            if new_name != row.name:
                session.execute(
                    update(RegisteredModelRow)
                    .where(RegisteredModelRow.id == row.registered_model_id)
                    .values(name=new_name)
                    .execution_options(synchronize_session=False)
                )
    except IntegrityError:
        raise ConflictError(
            f"a model named '{shorten(new_name)}' exists or existed (a name keeps its version "
            "numbers, which are not given again); choose another name"
        ) from None
    return get_model(store, version_label(new_name, version))


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


def _dataset_names(session: Session, rows: Sequence[ModelRow]) -> dict[int, str]:
    ids = {row.dataset_id for row in rows if row.dataset_id is not None}
    if not ids:
        return {}
    return dict(
        session.execute(select(DatasetRow.id, DatasetRow.name).where(DatasetRow.id.in_(ids))).all()
    )


def _aliases(session: Session, parents: Collection[int]) -> dict[tuple[int, int], tuple[str, ...]]:
    """(registered model id, version) -> the aliases that point at it, sorted."""
    if not parents:
        return {}
    found: dict[tuple[int, int], list[str]] = {}
    rows = session.execute(
        select(ModelAliasRow.registered_model_id, ModelAliasRow.version, ModelAliasRow.alias)
        .where(ModelAliasRow.registered_model_id.in_(parents))
        .order_by(ModelAliasRow.alias)
    )
    for parent, version, alias in rows:
        found.setdefault((parent, version), []).append(alias)
    return {key: tuple(aliases) for key, aliases in found.items()}


def _twins(session: Session, ids: Collection[int]) -> dict[int, TwinInfo]:
    """Model id -> its ONNX twin's description (the bytes are not read)."""
    if not ids:
        return {}
    rows = session.execute(
        select(ModelExportRow.model_id, ModelExportRow.sha256, ModelExportRow.size_bytes).where(
            ModelExportRow.model_id.in_(ids), ModelExportRow.format == TWIN_FORMAT
        )
    )
    return {model_id: TwinInfo(TWIN_FORMAT, sha256, size) for model_id, sha256, size in rows}


def version_info(
    session: Session,
    row: ModelRow,
    names: dict[int, str] | None = None,
    aliases: dict[tuple[int, int], tuple[str, ...]] | None = None,
    twins: dict[int, TwinInfo] | None = None,
) -> ModelInfo:
    """The description of the version ``row`` (``names``: data set names by id,
    ``aliases`` and ``twins``, when a listing read them for many rows at once)."""
    if names is None:
        names = _dataset_names(session, [row])
    if aliases is None:
        aliases = _aliases(session, {row.registered_model_id})
    if twins is None:
        twins = _twins(session, [row.id])
    return ModelInfo(
        id=row.id,
        name=row.name,
        version=row.version,
        aliases=aliases.get((row.registered_model_id, row.version), ()),
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
        twin=twins.get(row.id),
    )
