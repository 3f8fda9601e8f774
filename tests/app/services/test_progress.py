"""Progress told at most so often: the summary is built only when it is told."""

from __future__ import annotations

import pytest

from touchbench.app.services import progress
from touchbench.app.services.progress import throttled


def test_progress_is_summarised_and_told_at_most_every_so_many_seconds(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    clock = iter([100.0, 100.4, 100.9, 101.0, 101.5, 102.2, 102.3])
    monkeypatch.setattr(progress.time, "monotonic", lambda: next(clock))
    built: list[int] = []
    told: list[int] = []

    def summary() -> int:
        built.append(len(built))
        return len(built)

    tell = throttled(told.append, summary, seconds=1.0)
    for _ in range(7):
        tell()
    assert told == [1, 2, 3]  # at 100.0, 101.0 and 102.2: the others too soon
    assert len(built) == 3  # nothing built for a progress not told
