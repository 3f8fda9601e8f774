"""`touchbench import / datasets / show / export / delete` on SQLite and PostgreSQL."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.support.cli_runner import run_cli
from tests.support.synthetic import TOUCH_ARFF, write
from touchbench.benchmark.io.arff import read_arff


def test_import_prints_the_summary_as_json(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    path = write(tmp_path, "touch.arff", TOUCH_ARFF)
    result = run_cli(capsys, store_url, "import", str(path), "--json")
    assert result.code == 0, result.err
    summary = result.json()
    assert {k: summary[k] for k in ("name", "n_instances", "n_features", "targets")} == {
        "name": "touch",
        "n_instances": 4,
        "n_features": 3,
        "targets": ["gesture", "place"],
    }
    assert isinstance(summary["id"], int) and summary["created"] is True


def test_importing_the_same_file_again_returns_the_stored_dataset(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    path = write(tmp_path, "touch.arff", TOUCH_ARFF)
    first = run_cli(capsys, store_url, "import", str(path), "--json").json()
    again = run_cli(capsys, store_url, "import", str(path))
    assert again.code == 0
    assert "already stored as dataset" in again.err and f"{first['id']}" in again.err
    listing = run_cli(capsys, store_url, "datasets", "--json").json()
    assert [d["id"] for d in listing["datasets"]] == [first["id"]]


def test_targets_option_overrides_the_header(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    path = write(tmp_path, "touch.arff", TOUCH_ARFF)
    by_count = run_cli(capsys, store_url, "import", str(path), "--targets", "-1", "--json")
    assert by_count.json()["targets"] == ["mic"]
    other = write(tmp_path, "touch2.arff", TOUCH_ARFF.replace("0.5", "0.6"))
    by_name = run_cli(
        capsys, store_url, "import", str(other), "--targets", "place", "--name", "p", "--json"
    )
    assert by_name.json()["targets"] == ["place"]


def test_show_describes_schema_classes_and_missing_values(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    run_cli(capsys, store_url, "import", str(write(tmp_path, "touch.arff", TOUCH_ARFF)))
    shown = run_cli(capsys, store_url, "show", "touch", "--json").json()
    assert shown["class_distribution"] == {
        "gesture": {"tap": 2, "slap": 1, "soft stroke": 1},
        "place": {"head": 2, "arm": 2},
    }
    assert shown["missing_values"] == 3
    roles = {a["name"]: (a["role"], a["kind"], a["missing"]) for a in shown["attributes"]}
    assert roles["energy"] == ("feature", "numeric", 1)
    assert roles["place"] == ("target", "nominal", 0)
    table = run_cli(capsys, store_url, "show", "1")
    assert table.code == 0 and "soft stroke" in table.out


def test_export_then_reimport_gives_identical_data(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    source = write(tmp_path, "touch.arff", TOUCH_ARFF)
    run_cli(capsys, store_url, "import", str(source))
    exported = tmp_path / "out.arff"
    assert run_cli(capsys, store_url, "export", "touch", "-o", str(exported)).code == 0
    assert read_arff(exported).equals(read_arff(source))
    to_stdout = run_cli(capsys, store_url, "export", "touch")
    assert to_stdout.out == exported.read_text(encoding="utf-8")
    again = run_cli(capsys, store_url, "import", str(exported), "--name", "again", "--json")
    assert again.code == 0 and again.json()["created"] is True


def test_delete_removes_the_dataset(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    run_cli(capsys, store_url, "import", str(write(tmp_path, "touch.arff", TOUCH_ARFF)))
    assert run_cli(capsys, store_url, "delete", "touch").code == 0
    assert run_cli(capsys, store_url, "datasets", "--json").json() == {"datasets": []}
    missing = run_cli(capsys, store_url, "show", "touch")
    assert missing.code == 2 and "no dataset 'touch'" in missing.err


BAD_FILES = {
    "empty": ("empty.arff", b"", "empty"),
    "binary garbage": ("garbage.arff", bytes(range(256)) * 4, "not a text file"),
    "no @data": ("nodata.arff", "@relation r\n@attribute a numeric\n@attribute b {x,y}\n", "@data"),
    "too few values": (
        "few.arff",
        "@relation r\n@attribute a numeric\n@attribute b {x,y}\n@data\n1,x\n2\n",
        ":6:",
    ),
    "too many values": (
        "many.arff",
        "@relation r\n@attribute a numeric\n@attribute b {x,y}\n@data\n1,x,3\n",
        ":5:",
    ),
    "undeclared nominal": (
        "nominal.arff",
        "@relation r\n@attribute a numeric\n@attribute b {x,y}\n@data\n1,z\n",
        "'b'",
    ),
    "non-number": (
        "nan.arff",
        "@relation r\n@attribute a numeric\n@attribute b {x,y}\n@data\nabc,x\n",
        "'a'",
    ),
    "unterminated quote": (
        "quote.arff",
        "@relation r\n@attribute a numeric\n@attribute b {x,'y z}\n@data\n1,x\n",
        ":3:",
    ),
    "duplicate attribute": (
        "dup.arff",
        "@relation r\n@attribute a numeric\n@attribute a {x,y}\n@data\n1,x\n",
        "'a'",
    ),
    "-C too large": (
        "toomany.arff",
        "@relation 'r: -C 5'\n@attribute a numeric\n@attribute b {x,y}\n@data\n1,x\n",
        "-C 5",
    ),
    "ragged CSV": ("ragged.csv", "a,b,c\n1,2,x\n3,4\n", ":3"),
}


@pytest.mark.parametrize("case", sorted(BAD_FILES))
def test_bad_files_give_one_clear_line_exit_2_and_store_nothing(
    case: str, capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    name, content, expected = BAD_FILES[case]
    path = write(tmp_path, name, content)
    result = run_cli(capsys, store_url, "import", str(path))
    assert result.code == 2
    lines = result.err.strip().splitlines()
    assert len(lines) == 1, result.err
    assert lines[0].startswith("touchbench: error: ")
    assert expected in lines[0]
    assert "Traceback" not in result.err
    assert run_cli(capsys, store_url, "datasets", "--json").json() == {"datasets": []}


def test_a_missing_file_and_bad_usage_exit_2(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    missing = run_cli(capsys, store_url, "import", str(tmp_path / "nope.arff"))
    assert missing.code == 2 and "nope.arff" in missing.err and "no such file" in missing.err
    usage = run_cli(capsys, store_url, "import", "x.arff", "--format", "xlsx")
    assert usage.code == 2 and len(usage.err.strip().splitlines()) == 1
    assert usage.err.startswith("touchbench: error: --format: Input should be 'arff' or 'csv'")
    named = run_cli(capsys, store_url, "import", "x.arff", "--name", "12")
    assert named.code == 2
    assert named.err.startswith("touchbench: error: --name: a dataset name cannot be a number")
    unknown = run_cli(capsys, store_url, "frobnicate")
    assert unknown.code == 2 and "frobnicate" in unknown.err


@pytest.mark.shared
@pytest.mark.parametrize(
    "relative",
    [
        "uc3m-touch/mini/gesture_and_place.arff",
        "uc3m-touch/maggie/gesture_and_place.arff",
        "uc3m-touch/mini/weka_results_gesture.arff",
        "uc3m-touch/maggie/weka_results_place.arff",
    ],
)
def test_real_files_import_export_and_reimport_identically(
    relative: str,
    capsys: pytest.CaptureFixture[str],
    store_url: str,
    tmp_path: Path,
    shared_datasets: Path,
) -> None:
    source = shared_datasets / relative
    imported = run_cli(capsys, store_url, "import", str(source), "--json")
    assert imported.code == 0, imported.err
    expected = read_arff(source)
    assert imported.json()["n_instances"] == expected.n_instances
    exported = tmp_path / "export.arff"
    assert (
        run_cli(capsys, store_url, "export", str(imported.json()["id"]), "-o", str(exported)).code
        == 0
    )
    assert read_arff(exported).equals(expected)
    again = run_cli(capsys, store_url, "import", str(exported), "--name", "reimported", "--json")
    assert again.code == 0 and again.json()["created"] is True
    assert read_arff(exported).schema.target_names == expected.schema.target_names


@pytest.mark.shared
def test_the_damaged_reference_results_file_is_refused_at_its_line(
    capsys: pytest.CaptureFixture[str], store_url: str, shared_datasets: Path
) -> None:
    # Line 207 of this file is the tail of a row whose start is missing (the published
    # file is damaged); WEKA and liac-arff refuse it too.
    source = shared_datasets / "uc3m-touch/mini/weka_results_place.arff"
    result = run_cli(capsys, store_url, "import", str(source))
    assert result.code == 2
    assert "weka_results_place.arff:207: unterminated quote" in result.err
    assert run_cli(capsys, store_url, "datasets", "--json").json() == {"datasets": []}
