"""Work done ahead of a consumer by threads (benchmark/io/read_ahead.py): in order, bounded,
errors handed on, no thread left behind."""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator

import pytest

from touchbench.benchmark.io.read_ahead import ordered_ahead


def _read_ahead_threads() -> list[threading.Thread]:
    return [t for t in threading.enumerate() if t.name.startswith("read-ahead")]


def test_items_come_in_order_with_the_work_of_the_wanted_ones() -> None:
    def slow_square(n: int) -> int:
        time.sleep(0.01 * (n % 3))  # later items may finish first
        return n * n

    taken = list(ordered_ahead(range(20), slow_square, lambda n: n % 4 != 0))
    assert [item for item, _ in taken] == list(range(20))
    assert [None if f is None else f.result() for _, f in taken] == [
        None if n % 4 == 0 else n * n for n in range(20)
    ]
    assert _read_ahead_threads() == []


def test_no_more_than_ahead_items_are_taken_before_the_consumer_takes_one() -> None:
    taken: list[int] = []

    def source() -> Iterator[int]:
        for n in range(100):
            taken.append(n)
            yield n

    stream = ordered_ahead(source(), lambda n: n, lambda n: True, ahead=3)
    for expected, (item, future) in zip(range(10), stream, strict=False):
        assert item == expected
        assert future is not None and future.result() == expected
        assert len(taken) <= expected + 3
    stream.close()
    assert len(taken) <= 10 + 3
    assert _read_ahead_threads() == []


def test_what_the_work_raises_is_raised_by_its_result() -> None:
    def work(n: int) -> int:
        if n == 5:
            raise ValueError("block 5 is broken")
        return n

    results = []
    with pytest.raises(ValueError, match="block 5 is broken"):
        for _, future in ordered_ahead(range(10), work, lambda n: True):
            assert future is not None
            results.append(future.result())
    assert results == [0, 1, 2, 3, 4]
    assert _read_ahead_threads() == []


def test_a_consumer_that_stops_leaves_no_thread_and_no_work_running() -> None:
    started: list[int] = []
    release = threading.Event()

    def work(n: int) -> int:
        started.append(n)
        release.wait(5)
        return n

    stream = ordered_ahead(range(50), work, lambda n: True, workers=2, ahead=6)
    item, _ = next(stream)
    assert item == 0
    release.set()
    stream.close()  # what the store does when an import fails or is interrupted
    assert _read_ahead_threads() == []
    assert len(started) <= 6  # at most the items taken; the rest were never started


def test_an_error_in_the_source_stops_the_threads() -> None:
    def source() -> Iterator[int]:
        yield from range(4)
        raise OSError("read error")

    with pytest.raises(OSError, match="read error"):
        for _, future in ordered_ahead(source(), lambda n: n, lambda n: True):
            assert future is not None
            future.result()
    assert _read_ahead_threads() == []


def test_no_thread_is_started_when_no_item_is_wanted() -> None:
    started = threading.Event()
    real_start = threading.Thread.start

    def watched_start(thread: threading.Thread) -> None:
        if thread.name.startswith("read-ahead"):
            started.set()
        real_start(thread)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(threading.Thread, "start", watched_start)
        taken = list(ordered_ahead(range(5), lambda n: n, lambda n: False))
    assert [(item, future) for item, future in taken] == [(n, None) for n in range(5)]
    assert not started.is_set()
