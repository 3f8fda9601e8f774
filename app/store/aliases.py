"""Aliases of model versions: ``NAME@champion`` points at one version of the model ``NAME``;
:func:`set_alias` moves it and keeps its history, :func:`rollback_alias` steps back,
:func:`delete_alias` removes it.  An alias goes with the version it points at (a foreign
key), and its history with the registered model.

Each change holds the registered model while it reads and writes (as deleting and storing
versions do), so that changes from many clients at once are made one after the other.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

from sqlalchemy import delete, insert, select, update
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from touchbench.app.errors import AppError, ConflictError, FieldError, NotFoundError
from touchbench.app.schemas.models import AliasMoved
from touchbench.app.schemas.names import check_alias
from touchbench.app.schemas.references import parse_model_ref
from touchbench.app.store.database import Store
from touchbench.app.store.models import ModelInfo, held_version, version_info
from touchbench.app.store.naming import shorten
from touchbench.app.store.tables import ModelAliasEventRow, ModelAliasRow, ModelRow, utcnow

#: The alias ``promote`` sets and ``rollback`` steps back.
CHAMPION = "champion"
#: Attempts at a change of aliases that the store refused for a change made at once.
ALIAS_ATTEMPTS = 20
#: History steps read per query by :func:`_alias_steps`.
ALIAS_STEPS_PAGE = 16


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


def _checked(alias: str) -> str:
    try:
        return check_alias(alias)
    except AppError as error:
        raise FieldError("alias", str(error)) from None


def set_alias(store: Store, ref: str | int, alias: str) -> AliasMove:
    """Point ``NAME@alias`` at the version ``ref`` names, and note it in the alias's history.

    Raises
    ------
    FieldError
        An invalid alias (``alias``).
    NotFoundError
        No such model or version (deleted by a change made meanwhile, too).
    ConflictError
        ``ref`` was renamed meanwhile, or the store stayed too busy.
    """
    _checked(alias)

    def change(session: Session, row: ModelRow) -> AliasMove:
        parent = row.registered_model_id
        previous = _pointed_at(session, parent, alias)
        if previous is None:
            session.execute(
                insert(ModelAliasRow).values(
                    registered_model_id=parent, alias=alias, version=row.version, set_at=utcnow()
                )
            )
        else:
            _point(session, parent, alias, row.version)
        session.execute(
            insert(ModelAliasEventRow).values(
                registered_model_id=parent,
                alias=alias,
                version=row.version,
                set_at=utcnow(),
                undone=False,
            )
        )
        return AliasMove(alias, version_info(session, row), previous)

    return _changed(store, ref, change)


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

    def change(session: Session, row: ModelRow) -> AliasMove:
        parent, name = row.registered_model_id, row.name
        current = _pointed_at(session, parent, alias)
        if current is None:
            raise ConflictError(
                f"model '{shorten(name)}' has no alias '{alias}' to roll back (set it with "
                f"`promote` or `alias` first)"
            )
        undone: list[int] = []
        for step in _alias_steps(session, parent, alias):
            target = _version(session, parent, step.version) if step.version != current else None
            if target is not None:
                _undo(session, undone)
                _point(session, parent, alias, step.version)
                return AliasMove(alias, version_info(session, target), current)
            undone.append(step.id)  # the move being undone, or a version deleted since
        raise ConflictError(
            f"'{shorten(name)}@{alias}' has pointed at no other version that still exists "
            f"(now version {current}): nothing to roll back to"
        )

    return _changed(store, ref, change)


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
        No such model, or the model has no such alias (deleted meanwhile, too).
    ConflictError
        ``ref`` names a version the alias does not point at.
    """
    _checked(alias)

    def change(session: Session, row: ModelRow) -> AliasMove:
        parent, name = row.registered_model_id, row.name
        current = _pointed_at(session, parent, alias)
        if current is None:
            known = session.scalars(
                select(ModelAliasRow.alias)
                .where(ModelAliasRow.registered_model_id == parent)
                .order_by(ModelAliasRow.alias)
            ).all()
            raise NotFoundError(
                f"model '{shorten(name)}' has no alias '{alias}' (aliases: "
                f"{', '.join(known) or 'none'})"
            )
        if parse_model_ref(ref).pinned and current != row.version:
            raise ConflictError(
                f"'{shorten(name)}@{alias}' points at version {current}, not "
                f"{row.version}: not deleted (name the model without a version to delete it "
                "whatever it points at)"
            )
        target = _version(session, parent, current)
        assert target is not None  # an alias goes with its version (a foreign key)
        session.execute(
            update(ModelAliasEventRow)
            .where(
                ModelAliasEventRow.registered_model_id == parent,
                ModelAliasEventRow.alias == alias,
            )
            .values(undone=True)
        )
        session.execute(
            delete(ModelAliasRow).where(
                ModelAliasRow.registered_model_id == parent, ModelAliasRow.alias == alias
            )
        )
        return AliasMove(alias, version_info(session, target), current)

    return _changed(store, ref, change)


def _changed(
    store: Store, ref: str | int, change: Callable[[Session, ModelRow], AliasMove]
) -> AliasMove:
    """``change`` made to the aliases of the version ``ref`` names, in one transaction that
    holds its registered model first (:func:`app.store.models.held_version`): changes to one
    model's aliases from many clients at once happen one after the other, each answering
    for what the one before left (a 404 or 409, never a stale write).  A constraint the
    store still refuses (a version deleted by a process that did not hold the model) is
    tried again."""
    for _attempt in range(ALIAS_ATTEMPTS):
        try:
            with store.session() as session:
                return change(session, held_version(session, ref))
        except IntegrityError:
            continue
    raise ConflictError("the model's aliases kept changing meanwhile (busy store); try again")


def _pointed_at(session: Session, parent: int, alias: str) -> int | None:
    """The version ``alias`` points at now, None if it points at none."""
    return session.scalar(
        select(ModelAliasRow.version).where(
            ModelAliasRow.registered_model_id == parent, ModelAliasRow.alias == alias
        )
    )


def _point(session: Session, parent: int, alias: str, version: int) -> None:
    session.execute(
        update(ModelAliasRow)
        .where(ModelAliasRow.registered_model_id == parent, ModelAliasRow.alias == alias)
        .values(version=version, set_at=utcnow())
    )


def _undo(session: Session, steps: list[int]) -> None:
    """Mark the history ``steps`` (ids) undone."""
    if steps:
        session.execute(
            update(ModelAliasEventRow).where(ModelAliasEventRow.id.in_(steps)).values(undone=True)
        )


def _alias_steps(session: Session, parent: int, alias: str) -> Iterator[ModelAliasEventRow]:
    """The alias's moves not undone, newest first, read a page at a time: a rollback
    usually stops at the second, and an alias may have been moved very many times."""
    before: int | None = None
    while True:
        query = select(ModelAliasEventRow).where(
            ModelAliasEventRow.registered_model_id == parent,
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


def _version(session: Session, parent: int, version: int) -> ModelRow | None:
    return session.scalars(
        select(ModelRow).where(ModelRow.registered_model_id == parent, ModelRow.version == version)
    ).first()
