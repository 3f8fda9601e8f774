"""The election of the dispatching process, with two contenders in this process on one
address: one leads, the other wakes it, and takes its place once it lets go."""

from __future__ import annotations

import threading
import uuid
from collections.abc import Iterator

import pytest

from touchbench.app.jobs.leadership import Leadership, address_for

#: A deadlock guard, not a measure: a wake-up ends a wait of this length far sooner.
LONG = 600.0


@pytest.fixture
def address() -> str:
    return f"\0touchbench-test-{uuid.uuid4().hex}"


@pytest.fixture
def contenders(address: str) -> Iterator[tuple[Leadership, Leadership]]:
    first, second = Leadership(address, "store"), Leadership(address, "store")
    yield first, second
    first.release()
    second.release()


def _waits_until_woken(leadership: Leadership, wake: Leadership) -> bool:
    """Whether ``leadership.wait(LONG)`` ends after ``wake.wake()``."""
    waiting = threading.Thread(target=leadership.wait, args=(LONG,), daemon=True)
    waiting.start()
    wake.wake()
    waiting.join(timeout=60)
    return not waiting.is_alive()


def test_one_of_two_leads_hears_the_other_and_is_replaced_when_it_lets_go(
    contenders: tuple[Leadership, Leadership],
) -> None:
    first, second = contenders
    assert first.dispatches() and first.leading
    assert not second.dispatches()  # the holder runs as this user: it dispatches for both
    assert not second.leading
    assert _waits_until_woken(first, second)  # a wake-up reaches the holder's wait

    first.release()
    assert not first.leading
    assert second.dispatches() and second.leading
    assert not first.dispatches()  # the address is taken again, by a process of this user
    assert _waits_until_woken(second, first)


def test_a_wake_ends_ones_own_wait_without_an_address() -> None:
    alone = Leadership(None, "memory store")
    assert alone.leading and alone.dispatches()
    assert _waits_until_woken(alone, alone)


def test_a_process_that_does_not_lead_still_wakes_from_its_own_wake(
    contenders: tuple[Leadership, Leadership],
) -> None:
    first, second = contenders
    assert first.dispatches() and not second.dispatches()
    assert _waits_until_woken(second, second)  # stop() of a follower ends its wait


def test_an_address_names_one_store() -> None:
    one = "postgresql+psycopg://u:p@127.0.0.1:5432/one"
    other = "postgresql+psycopg://u:p@127.0.0.1:5432/other"
    assert address_for(one) == address_for(one) != address_for(other)
    assert address_for("sqlite://") is None  # each process has an in-memory store of its own
