"""Aliases of model versions: ``NAME@champion`` points at one version of the model ``NAME``;
:func:`set_alias` moves it and keeps its history, :func:`rollback_alias` steps back,
:func:`delete_alias` removes it.  An alias goes with the version it points at (a foreign
key), and its history with the registered model.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

from sqlalchemy import select, update
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from touchbench.app.errors import AppError, ConflictError, FieldError, NotFoundError
from touchbench.app.schemas.models import AliasMoved
from touchbench.app.schemas.names import check_alias
from touchbench.app.schemas.references import parse_model_ref
from touchbench.app.store.database import Store
from touchbench.app.store.models import ModelInfo, version_info, version_row
from touchbench.app.store.naming import shorten
from touchbench.app.store.tables import ModelAliasEventRow, ModelAliasRow, ModelRow, utcnow

#: The alias ``promote`` sets and ``rollback`` steps back.
CHAMPION = "champion"
#: Attempts at setting an alias that other processes set at once.
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
        No such model or version.
    """
    _checked(alias)
    for _attempt in range(ALIAS_ATTEMPTS):
        try:
            with store.session() as session:
                row = version_row(session, ref)
                current = _alias_row(session, row.registered_model_id, alias)
                previous = None if current is None else current.version
                if current is None:
                    session.add(
                        ModelAliasRow(
                            registered_model_id=row.registered_model_id,
                            alias=alias,
                            version=row.version,
                        )
                    )
                else:
                    current.version = row.version
                    current.set_at = utcnow()
                session.add(
                    ModelAliasEventRow(
                        registered_model_id=row.registered_model_id,
                        alias=alias,
                        version=row.version,
                    )
                )
                session.flush()  # a concurrent first setting of the alias: try again
                return AliasMove(alias, version_info(session, row), previous)
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
        row = version_row(session, ref)
        parent, name = row.registered_model_id, row.name
        current = _alias_row(session, parent, alias)
        if current is None:
            raise ConflictError(
                f"model '{shorten(name)}' has no alias '{alias}' to roll back (set it with "
                f"`promote` or `alias` first)"
            )
        for step in _alias_steps(session, parent, alias):
            target = (
                _version(session, parent, step.version) if step.version != current.version else None
            )
            if target is not None:
                previous, current.version, current.set_at = current.version, step.version, utcnow()
                return AliasMove(alias, version_info(session, target), previous)
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
    _checked(alias)
    with store.session() as session:
        row = version_row(session, ref)
        parent, name = row.registered_model_id, row.name
        current = _alias_row(session, parent, alias)
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
        if parse_model_ref(ref).pinned and current.version != row.version:
            raise ConflictError(
                f"'{shorten(name)}@{alias}' points at version {current.version}, not "
                f"{row.version}: not deleted (name the model without a version to delete it "
                "whatever it points at)"
            )
        target = _version(session, parent, current.version)
        assert target is not None  # an alias goes with its version (a foreign key)
        session.execute(
            update(ModelAliasEventRow)
            .where(
                ModelAliasEventRow.registered_model_id == parent,
                ModelAliasEventRow.alias == alias,
            )
            .values(undone=True)
        )
        session.delete(current)
        return AliasMove(alias, version_info(session, target), current.version)


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


def _alias_row(session: Session, parent: int, alias: str) -> ModelAliasRow | None:
    return session.get(ModelAliasRow, (parent, alias))


def _version(session: Session, parent: int, version: int) -> ModelRow | None:
    return session.scalars(
        select(ModelRow).where(ModelRow.registered_model_id == parent, ModelRow.version == version)
    ).first()
