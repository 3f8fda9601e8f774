"""Versions of a model and their aliases, in the store (SQLite and PostgreSQL): references
(``NAME``, ``NAME@VERSION``, ``NAME@ALIAS``, ids), alias moves and rollbacks, names with
``@`` refused, and versions stored by two processes at once."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from sqlalchemy import select
from sqlalchemy.orm import Session

from tests.support.cli_runner import run_cli
from touchbench.app.errors import ConflictError, FieldError, NotFoundError
from touchbench.app.schemas.models import TrainRequest
from touchbench.app.store import aliases as store_aliases
from touchbench.app.store import models as store_models
from touchbench.app.store.aliases import delete_alias, rollback_alias, set_alias
from touchbench.app.store.database import Store
from touchbench.app.store.model_refs import model_version
from touchbench.app.store.models import (
    ModelInfo,
    delete_model,
    get_model,
    list_models,
    save_model,
)
from touchbench.app.store.tables import DatasetRow, ModelRow, RegisteredModelRow

REPOSITORY = Path(__file__).resolve().parents[3]


def _save(
    store: Store, name: str | None = "mic", dataset_id: int | None = None, classifier: str = "nb"
) -> int:
    return _saved(store, name, dataset_id, classifier).version


def _saved(
    store: Store, name: str | None = "mic", dataset_id: int | None = None, classifier: str = "nb"
) -> ModelInfo:
    return save_model(
        store,
        classifier=classifier,
        params={},
        schema={"relation": "r", "attributes": []},
        targets=["gesture"],
        artifact=b"artifact",
        name=name,
        dataset_id=dataset_id,
    )


def test_references_name_versions_and_aliases(store: Store) -> None:
    assert [_save(store) for _ in range(3)] == [1, 2, 3]
    ids = [model.id for model in list_models(store)]
    assert model_version(store, "mic")[2] == "mic@3"  # a name alone: the newest version
    assert model_version(store, "mic@latest")[2] == "mic@3"
    assert model_version(store, "mic@2") == (ids[1], model_version(store, ids[1])[1], "mic@2", None)
    assert get_model(store, "mic@1").id == ids[0] and get_model(store, ids[2]).version == 3
    with pytest.raises(NotFoundError, match=r"model 'mic' has no version 7 \(versions: 1, 2, 3\)"):
        get_model(store, "mic@7")
    with pytest.raises(NotFoundError, match="model 'mic' has no alias 'champion'"):
        model_version(store, "mic@champion")
    with pytest.raises(NotFoundError, match="no model 'other'"):
        get_model(store, "other@1")


def test_alias_moves_and_rollback_steps_back_through_its_history(store: Store) -> None:
    for _ in range(4):
        _save(store)
    moves = [set_alias(store, f"mic@{version}", "champion") for version in (1, 2, 3)]
    assert [(m.model.version, m.previous) for m in moves] == [(1, None), (2, 1), (3, 2)]
    set_alias(store, "mic@4", "staging")
    assert model_version(store, "mic@champion")[2] == "mic@3"
    listed = {m.version: m.aliases for m in list_models(store)}
    assert listed == {1: (), 2: (), 3: ("champion",), 4: ("staging",)}

    back = rollback_alias(store, "mic")
    assert (back.model.label, back.previous) == ("mic@2", 3)
    assert model_version(store, "mic@champion")[2] == "mic@2"
    delete_model(store, "mic@1")  # rollback skips a version deleted since
    with pytest.raises(ConflictError, match="nothing to roll back to"):
        rollback_alias(store, "mic@champion")
    assert model_version(store, "mic@champion")[2] == "mic@2"  # a refused rollback moves nothing
    assert set_alias(store, "mic@4", "champion").previous == 2
    assert rollback_alias(store, "mic").model.label == "mic@2"  # 3 was undone before

    with pytest.raises(ConflictError, match="nothing to roll back to"):
        rollback_alias(store, "mic", "staging")  # it only ever pointed at version 4
    with pytest.raises(ConflictError, match="no alias 'beta' to roll back"):
        rollback_alias(store, "mic", "beta")
    delete_model(store, "mic@2")  # its alias goes with it
    with pytest.raises(NotFoundError, match="has no alias 'champion'"):
        get_model(store, "mic@champion")


def test_an_alias_is_deleted_and_set_again_starts_afresh(store: Store) -> None:
    for _ in range(3):
        _save(store)
    for version in (1, 2):
        set_alias(store, f"mic@{version}", "champion")
    with pytest.raises(ConflictError, match=r"'mic@champion' points at version 2, not 1"):
        delete_alias(store, "mic@1", "champion")  # moved since the caller looked
    assert model_version(store, "mic@champion")[2] == "mic@2"
    gone = delete_alias(store, "mic@2", "champion")
    assert (gone.alias, gone.model.label, gone.previous) == ("champion", "mic@2", 2)
    with pytest.raises(NotFoundError, match=r"model 'mic' has no alias 'champion' \(aliases: none"):
        delete_alias(store, "mic", "champion")
    with pytest.raises(NotFoundError, match="has no alias 'champion'"):
        model_version(store, "mic@champion")
    with pytest.raises(FieldError, match="'latest' is not an alias"):
        delete_alias(store, "mic", "latest")
    with pytest.raises(NotFoundError, match="no model 'other'"):
        delete_alias(store, "other", "champion")
    # set again: its history before the deletion is not stepped back into
    assert set_alias(store, "mic@3", "champion").previous is None
    with pytest.raises(ConflictError, match="nothing to roll back to"):
        rollback_alias(store, "mic")
    set_alias(store, "mic@1", "staging")
    assert delete_alias(store, "mic", "staging").model.label == "mic@1"  # a name: any version
    assert {m.version: m.aliases for m in list_models(store)} == {
        1: (),
        2: (),
        3: ("champion",),
    }


def test_a_rollback_reads_the_history_a_page_at_a_time(
    store: Store, monkeypatch: pytest.MonkeyPatch
) -> None:
    """An alias moved many times (a flood of promotes) is stepped back reading a few of
    its moves, and across pages when the newest ones are all the same version."""
    from sqlalchemy import event
    from sqlalchemy.orm import Session

    from touchbench.app.store.tables import ModelAliasEventRow

    for _ in range(3):
        _save(store)
    set_alias(store, "mic@1", "champion")
    for _ in range(5):
        set_alias(store, "mic@2", "champion")  # the same version, moved to again
    for version in [3, 2] * 40:
        set_alias(store, f"mic@{version}", "champion")
    loaded: list[object] = []

    def count(session: Session, instance: object) -> None:
        if isinstance(instance, ModelAliasEventRow):
            loaded.append(instance)

    event.listen(Session, "loaded_as_persistent", count)
    try:
        assert rollback_alias(store, "mic").model.label == "mic@3"
    finally:
        event.remove(Session, "loaded_as_persistent", count)
    assert 0 < len(loaded) <= store_aliases.ALIAS_STEPS_PAGE  # not the 86 moves
    monkeypatch.setattr(store_aliases, "ALIAS_STEPS_PAGE", 2)
    for version in (2, 1):  # back over the moves to 2 (undone, then equal), pages of 2
        set_alias(store, f"mic@{version}", "champion")
    set_alias(store, "mic@2", "champion")
    set_alias(store, "mic@2", "champion")
    assert rollback_alias(store, "mic").model.label == "mic@1"


def test_a_deleted_version_and_its_id_never_come_back(store: Store) -> None:
    """Issue 36: delete ``pin@2`` (the newest), train ``pin`` again with another
    classifier: it is ``pin@3`` with an id of its own, and ``rollback`` does not move the
    champion onto it (nobody promoted it)."""
    assert [_save(store, "pin"), _save(store, "pin")] == [1, 2]
    set_alias(store, "pin@2", "champion")
    set_alias(store, "pin@1", "champion")
    gone = delete_model(store, "pin")
    assert gone.label == "pin@2"
    again = _saved(store, "pin", classifier="j48")
    assert again.label == "pin@3" and again.id > gone.id
    with pytest.raises(NotFoundError, match=r"model 'pin' has no version 2 \(versions: 1, 3\)"):
        get_model(store, "pin@2")
    with pytest.raises(NotFoundError):
        get_model(store, gone.id)
    with pytest.raises(ConflictError, match="nothing to roll back to"):
        rollback_alias(store, "pin")
    assert model_version(store, "pin@champion")[2] == "pin@1"

    # every version deleted: the name keeps its count, and so do the ids
    newest = again.id
    for ref in ("pin@3", "pin@1"):
        delete_model(store, ref)
    with pytest.raises(NotFoundError, match=r"'pin' has no versions left \(versions up to 3"):
        get_model(store, "pin")
    with pytest.raises(NotFoundError, match=r"'pin' has no version 1 \(versions: none left\)"):
        get_model(store, "pin@1")
    fresh = _saved(store, "pin")
    assert fresh.label == "pin@4" and fresh.id > newest
    assert [m.label for m in list_models(store)] == ["pin@4"]


def test_aliases_that_would_read_otherwise_are_refused(store: Store) -> None:
    _save(store)
    for alias in ["3", "latest", "", "with space", "x" * 101]:
        with pytest.raises(FieldError) as refused:
            set_alias(store, "mic@1", alias)
        assert refused.value.field == "alias", alias


def test_names_with_at_are_refused_where_they_would_be_ambiguous(store: Store) -> None:
    with pytest.raises(FieldError, match="a model name cannot hold '@'"):
        TrainRequest(dataset="touch", classifier="nb", name="mic@2")
    with pytest.raises(FieldError, match="a model name cannot hold '@'"):
        _save(store, "mic@champion")
    with store.session() as session:  # a data set's name may hold '@': the default folds it
        session.add(
            DatasetRow(
                name="lab@home",
                relation="r",
                schema={},
                target_names=[],
                n_instances=0,
                n_attributes=0,
                sha256="0" * 64,
            )
        )
    assert [_save(store, None, dataset_id=1) for _ in range(2)] == [1, 2]
    assert model_version(store, "lab_home-nb@2")[2] == "lab_home-nb@2"
    # a model stored with '@' before the rule is still found by its whole name
    with store.session() as session:
        old = RegisteredModelRow(name="old@name", last_version=1)
        session.add(old)
        session.flush()
        session.add(
            ModelRow(
                registered_model_id=old.id,
                version=1,
                classifier="nb",
                params={},
                schema={},
                targets=[],
                sha256="0" * 64,
                size_bytes=0,
            )
        )
    assert get_model(store, "old@name").name == "old@name"


def test_a_name_registered_meanwhile_is_retried(
    store: Store, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Another process registers the name between this one's look and its insert."""
    real = store_models._register
    first = iter([True])

    def late(session: Session, name: str) -> int:
        if next(first, False):
            with store.session() as other:  # the other process registers it...
                other.add(RegisteredModelRow(name=name, last_version=0))
            # ... after this one looked and found nothing
            session.add(RegisteredModelRow(name=name, last_version=0))
            session.flush()
        return real(session, name)

    monkeypatch.setattr(store_models, "_register", late)
    assert [_save(store), _save(store)] == [1, 2]
    with store.session() as session:
        versions = session.scalars(select(ModelRow.version).order_by(ModelRow.id)).all()
        parents = session.scalars(select(RegisteredModelRow.last_version)).all()
    assert versions == [1, 2] and parents == [2]


SAVER = """
import sys
from touchbench.app.store.database import Store
from touchbench.app.store.models import save_model
store = Store(sys.argv[1])
print(sys.argv[2], flush=True)
sys.stdin.readline()  # both processes start saving together
for _ in range(int(sys.argv[3])):
    save_model(store, classifier="nb", params={}, schema={}, targets=["g"],
               artifact=sys.argv[2].encode(), name="mic")
"""


def test_two_processes_storing_one_name_get_distinct_versions(store_url: str) -> None:
    Store(store_url).dispose()  # migrated before the race
    each = 6
    savers = [
        subprocess.Popen(
            [sys.executable, "-c", SAVER, store_url, tag, str(each)],
            cwd=REPOSITORY,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
        )
        for tag in ("a", "b")
    ]
    for saver in savers:  # both have opened the store
        assert saver.stdout is not None and saver.stdout.readline().strip()
    for saver in savers:
        assert saver.stdin is not None
        saver.stdin.write("go\n")
        saver.stdin.close()
    assert [saver.wait(timeout=120) for saver in savers] == [0, 0]
    store = Store(store_url)
    try:
        versions = sorted(m.version for m in list_models(store))
    finally:
        store.dispose()
    assert versions == list(range(1, 2 * each + 1))


def test_the_cli_promotes_aliases_and_rolls_back(
    capsys: pytest.CaptureFixture[str], store: Store, store_url: str
) -> None:
    for _ in range(3):
        _save(store)
    assert run_cli(capsys, store_url, "promote", "mic@1").code == 0
    promoted = run_cli(capsys, store_url, "promote", "mic@3", "--json")
    assert promoted.json() == {"alias": "champion", "model": "mic@3", "version": 3, "previous": 1}
    aliased = run_cli(capsys, store_url, "alias", "mic@2", "staging")
    assert aliased.code == 0 and "mic@staging is now version 2" in aliased.err
    listing = run_cli(capsys, store_url, "models", "--json").json()["models"]
    assert [(m["version"], m["aliases"]) for m in listing] == [
        (1, []),
        (2, ["staging"]),
        (3, ["champion"]),
    ]
    back = run_cli(capsys, store_url, "rollback", "mic")
    assert back.code == 0 and "mic@champion is now version 1 (was version 3)" in back.err
    deleted = run_cli(capsys, store_url, "alias", "--delete", "mic", "staging")
    assert deleted.code == 0 and "deleted mic@staging (it pointed at version 2)" in deleted.err
    as_json = run_cli(capsys, store_url, "alias", "mic", "champion", "--delete", "--json")
    assert as_json.json() == {"alias": "champion", "model": "mic@1", "version": 1}
    assert run_cli(capsys, store_url, "promote", "mic@3").code == 0
    refused = [
        (("alias", "--delete", "mic", "staging"), "model 'mic' has no alias 'staging'"),
        (("alias", "--delete", "mic@2", "champion"), "points at version 3, not 2"),
        (("alias", "--delete", "mic", "latest"), "'latest' is not an alias"),
        (("alias", "mic@2", "2"), "ALIAS: an alias starts with a letter"),
        (("promote", "mic@9"), "model 'mic' has no version 9"),
        (("rollback", "mic"), "nothing to roll back to"),  # set again after its deletion
        (("rollback", "mic", "--alias", "beta"), "no alias 'beta' to roll back"),
    ]
    for args, words in refused:
        result = run_cli(capsys, store_url, *args)
        assert result.code == 2 and words in result.err, (args, result.err)
        assert len(result.err.strip().splitlines()) == 1
