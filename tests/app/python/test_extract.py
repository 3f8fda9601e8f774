"""``touchbench.simulate`` and ``touchbench.extract`` from Python, on SQLite and PostgreSQL: the
table comes back as a DataFrame with each event's recording as its group, is kept in the
store, and leave-one-group-out on it leaves one recording out at a time."""

from __future__ import annotations

from pathlib import Path

import pytest

import touchbench
from tests.support.cli_runner import run_cli
from touchbench.app.errors import FieldError


def test_extracted_recordings_are_the_groups_of_their_events(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    recordings, labels = touchbench.simulate(tmp_path / "sessions", trials=3, touches=6)
    assert [p.name for p in recordings] == ["session1.wav", "session2.wav", "session3.wav"]
    touches = touchbench.extract(recordings, labels=labels, extractor="uc3m-audio", name="taps",
                                 store=store_url)  # fmt: skip
    assert touches.attrs["dataset"] == "taps" and len(touches) == 18
    assert sorted(touches["group"].unique()) == [p.name for p in recordings]
    assert {"gesture", "place"} <= set(touches.columns)
    listed = run_cli(capsys, store_url, "datasets", "--json").json()["datasets"]
    assert [d["name"] for d in listed] == ["taps"]

    board = touchbench.bench("taps", target="gesture", classifiers=["nb", "zeror"],
                             folds="logo", store=store_url, progress=False)  # fmt: skip
    assert board.schema.folds == "leave-one-group-out, 3 groups"
    assert set(board.to_pandas()["folds"]) == {3}


def test_simulate_refuses_what_it_cannot_write(tmp_path: Path) -> None:
    with pytest.raises(FieldError) as refused:
        touchbench.simulate(tmp_path, "sonar")  # type: ignore[arg-type]
    assert refused.value.field == "sensor"
    with pytest.raises(FieldError) as refused:
        touchbench.simulate(tmp_path, trials=0)
    assert refused.value.field == "trials"
