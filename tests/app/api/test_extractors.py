"""``GET /api/extractors`` (the same object as ``extractors --json``) and CSV time-series
options of a recording upload."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from tests.support.cli_runner import run_cli
from tests.support.csvfiles import write_biotac_csv
from tests.support.service import Server, finished


def test_extractors_are_listed_as_the_cli_lists_them(
    capsys: pytest.CaptureFixture[str], make_sqlite_server: Callable[..., Server], tmp_path: Path
) -> None:
    server = make_sqlite_server()
    listed = server.client.get("/api/extractors", params={"samplerate": 100})
    assert listed.status_code == 200, listed.text
    body = listed.json()
    cli = run_cli(capsys, server.database_url, "extractors", "--samplerate", "100", "--json")
    assert cli.code == 0 and cli.json() == body
    taxel = next(e for e in body["extractors"] if e["name"] == "taxel-dft")
    drop = next(o for o in taxel["options"] if o["name"] == "drop")
    assert (drop["type"], drop["default"], drop["at_rate"]) == ("integer >= 0", None, 1)
    assert "4 from 400 Hz up" in drop["default_text"]
    at_800 = server.client.get("/api/extractors", params={"samplerate": 800}).json()
    taxel = next(e for e in at_800["extractors"] if e["name"] == "taxel-dft")
    assert next(o for o in taxel["options"] if o["name"] == "drop")["at_rate"] == 4
    refused = server.client.get("/api/extractors", params={"samplerate": -1})
    assert refused.status_code == 422, refused.text
    assert refused.json()["error"]["where"] == "query.samplerate"

    # A tactile export uploaded with its CSV options: names kept, the jitter noted.
    path = tmp_path / "slip.csv"
    write_biotac_csv(path, np.random.default_rng(0).standard_normal((3, 400)))
    with path.open("rb") as handle:
        response = server.client.post(
            "/api/datasets/recordings",
            files=[("recordings", (path.name, handle))],
            data={
                "extractor": "window",
                "events": "none",
                "segment": "1",
                "fields": ["pdc", "tac"],
                "name": "slip",
            },
        )
    assert response.status_code == 202, response.text
    job = server.wait_for(f"/api/jobs/{response.json()['job']}", finished)
    assert job["status"] == "done", job
    assert any("resampled" in note for note in job["result"]["notes"]), job["result"]
    names = [a["name"] for a in server.client.get("/api/datasets/slip").json()["attributes"]]
    assert names[:2] == ["t0_pdc", "t1_pdc"] and names[25] == "t0_tac"
