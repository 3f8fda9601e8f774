"""The life of a run (app/store/states.py) on SQLite and PostgreSQL: cancelling, resume
after a cancel, claims by a second process, and what a lost process leaves."""

from __future__ import annotations

import ast
import re
import subprocess
import sys
from pathlib import Path

import grimp
import pytest

import touchbench.app
from tests.support.synthetic import small_dataset
from touchbench.app.errors import ConflictError
from touchbench.app.schemas.run_config import RunConfig
from touchbench.app.schemas.status import Status
from touchbench.app.store.database import Store
from touchbench.app.store.datasets import add_dataset
from touchbench.app.store.ownership import process_owner
from touchbench.app.store.runs import (
    claim_run,
    create_run,
    finish_run,
    get_run,
    heartbeat,
    mark_lost_runs,
    request_cancel,
    requeue_run,
    should_stop,
)
from touchbench.app.store.states import RunBusy


def _run(store: Store) -> int:
    info, _ = add_dataset(store, small_dataset(), sha256="1" * 64, name="touch")
    run = create_run(
        store,
        dataset_id=info.id,
        kind="multiclass",
        targets=["c"],
        classifiers=["nb"],
        config=RunConfig(folds=2, repeats=1, seed=0, n_tasks=2),
    )
    return run.id


def _dead_owner() -> str:
    """The owner name of a process on this host that has ended."""
    ended = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"],
        check=True,
        capture_output=True,
        text=True,
    )
    host = process_owner().split(":", 1)[0]
    return f"{host}:{ended.stdout.strip()}@1"


def test_a_cancel_of_a_running_run_is_cancelling_until_its_process_stops(store: Store) -> None:
    run_id = _run(store)
    owner = process_owner()
    claim_run(store, run_id, owner=owner)
    assert not should_stop(store, run_id, owner)
    asked = request_cancel(store, run_id)
    assert (asked.status, asked.cancel_requested) == ("cancelling", True)
    assert get_run(store, run_id).status == "cancelling"
    assert should_stop(store, run_id, owner) and heartbeat(store, run_id, owner)
    again = request_cancel(store, run_id)  # asked twice: the same answer, no error
    assert again.status == "cancelling"
    with pytest.raises(ConflictError, match=f"run {run_id} is being cancelled; resume it once"):
        requeue_run(store, run_id)
    with pytest.raises(ConflictError, match="is being cancelled"):
        claim_run(store, run_id, owner="elsewhere:1@1")
    finish_run(store, run_id, "cancelled")  # what the run's process does when it stops
    with pytest.raises(ConflictError, match=f"run {run_id} is already cancelled"):
        request_cancel(store, run_id)
    assert requeue_run(store, run_id).status == "queued"
    with pytest.raises(ConflictError, match="is queued already"):
        requeue_run(store, run_id)


def test_a_run_another_live_process_executes_is_not_claimed(store: Store) -> None:
    run_id = _run(store)
    claim_run(store, run_id, owner=process_owner())
    with pytest.raises(RunBusy, match=f"run {run_id} is being executed by "):
        claim_run(store, run_id, owner="elsewhere:1@1")
    with pytest.raises(ConflictError, match="is running; nothing to resume"):
        requeue_run(store, run_id)
    finish_run(store, run_id, "done")
    for refused in (request_cancel, requeue_run):
        with pytest.raises(ConflictError, match=f"run {run_id} is (already )?done"):
            refused(store, run_id)


@pytest.mark.parametrize(("asked", "left"), [(False, "interrupted"), (True, "cancelled")])
def test_a_lost_process_leaves_its_run_interrupted_or_cancelled(
    store: Store, asked: bool, left: str
) -> None:
    run_id = _run(store)
    dead = _dead_owner()
    claim_run(store, run_id, owner=dead)
    if asked:  # the cancel was asked while the process lived; it died before it stopped
        from sqlalchemy import update

        from touchbench.app.store.tables import RunRow

        with store.session() as session:
            session.execute(update(RunRow).values(status="cancelling", cancel_requested=True))
    assert mark_lost_runs(store) == [run_id]
    run = get_run(store, run_id)
    assert (run.status, run.owner) == (left, None) and run.finished_at is not None
    assert requeue_run(store, run_id).status == "queued"
    claimed = claim_run(store, run_id, owner=process_owner())  # and a new process takes it
    assert claimed.status == "running"


#: Strings in app/ that are the words of a status without being one: an ablation entry's
#: verdict and the count of tasks a partial answer has done.
NOT_A_STATUS = {("services/ablation.py", "failed"), ("cli/progress.py", "done")}


def test_a_status_is_spelt_in_app_schemas_status_only() -> None:
    """Every other module names the statuses and their sets through app.schemas.status."""
    app = Path(touchbench.app.__file__).resolve().parent
    words = {status.value for status in Status}
    spelt = set()
    for path in app.rglob("*.py"):
        where = str(path.relative_to(app))
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Constant) and node.value in words:
                spelt.add((where, node.value))
    for path in app.rglob("*.j2"):
        where = str(path.relative_to(app))
        spelt |= {
            (where, word) for word in words if re.search(f"['\"]{word}['\"]", path.read_text())
        }
    assert {place for place in spelt if place[0] != "schemas/status.py"} == NOT_A_STATUS
    assert {word for where, word in spelt if where == "schemas/status.py"} == words


def test_the_rules_of_states_sit_below_the_runs_and_the_queue_that_apply_them() -> None:
    """No import circle among app.store.states, runs and queue (imports under
    TYPE_CHECKING and inside functions count)."""
    graph = grimp.build_graph("touchbench", include_external_packages=False)
    below = {
        "touchbench.app.store.states": {"runs", "queue", "jobs"},
        "touchbench.app.store.queue": {"runs", "jobs"},
    }
    for module, above in below.items():
        for name in above:
            assert not graph.chain_exists(module, f"touchbench.app.store.{name}"), (module, name)
