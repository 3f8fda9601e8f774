"""Tables from other labs over HTTP: the upload form's ``groups`` and ``ignore`` fields, the
groups a data set's description shows, and column choices refused with 422 naming the field
and the column, nothing stored; on a real service over SQLite (the store's round trip of
groups: tests/app/store/test_round_trips.py)."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.support.cli_runner import run_cli
from tests.support.grasp_table import FEATURES, grasp_arff, grasp_csv
from tests.support.service import Server, upload


def test_an_upload_sets_the_group_column_and_ignored_columns_aside(
    capsys: pytest.CaptureFixture[str], sqlite_server: Server, tmp_path: Path
) -> None:
    path = grasp_csv(tmp_path / "grasps.csv")
    response = upload(sqlite_server, path, groups="object", ignore="trial")
    assert response.status_code == 201, response.text
    created = response.json()
    assert (created["n_instances"], created["n_features"]) == (80, 6)
    assert created["groups"] == {"count": 8, "column": "object"}

    described = sqlite_server.client.get("/api/datasets/grasps").json()
    assert described["groups"] == {"count": 8, "column": "object"}
    assert [a["name"] for a in described["attributes"]] == [*FEATURES, "slipped"]
    assert (
        described == run_cli(capsys, sqlite_server.database_url, "show", "grasps", "--json").json()
    )

    plain = upload(sqlite_server, grasp_arff(tmp_path / "plain.arff"))
    assert plain.status_code == 201, plain.text
    assert plain.json()["groups"] is None and plain.json()["n_features"] == 8
    assert sqlite_server.client.get("/api/datasets/plain").json()["groups"] is None


@pytest.mark.parametrize("name", ["grasps.csv", "grasps.arff"])
def test_column_choices_that_do_not_fit_are_422_naming_the_field_and_store_nothing(
    sqlite_server: Server, tmp_path: Path, name: str
) -> None:
    write = grasp_csv if name.endswith(".csv") else grasp_arff
    path = write(tmp_path / name)
    refusals = [
        ({"groups": "objekt"}, "body.groups", "no column named 'objekt' in grasps."),
        ({"ignore": "trial,trail"}, "body.ignore", "no column named 'trail' in grasps."),
        ({"groups": "slipped"}, "body.groups", "column 'slipped' of grasps."),
        ({"groups": "object", "ignore": "object"}, "body.ignore", "names the groups"),
        ({"ignore": "slipped"}, "body.ignore", "a target cannot be ignored"),
        (
            {"ignore": ",".join(["object", "trial", *FEATURES, "slipped"])},
            "body.ignore",
            "every column of grasps.",
        ),
        (
            {"groups": "object", "ignore": ",".join(["trial", *FEATURES])},
            "body.ignore",
            "no feature is left",
        ),
    ]
    for fields, where, words in refusals:
        response = upload(sqlite_server, path, **fields)
        assert response.status_code == 422, (fields, response.text)
        error = response.json()["error"]
        assert error["where"] == where and words in error["message"], (fields, error)
        assert (
            str(sqlite_server.work_dir) not in error["message"] and "upload" not in error["message"]
        )
    assert sqlite_server.client.get("/api/datasets").json() == {"datasets": []}
    assert not [p for p in sqlite_server.work_dir.glob("**/*") if p.is_file()]
