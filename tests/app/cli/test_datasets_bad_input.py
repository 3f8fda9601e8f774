"""Issue 8, the data-set parts: names, bounded input, ordinary errors, silent data changes,
display; every case through the CLI on SQLite and PostgreSQL."""

from __future__ import annotations

import os
import re
import subprocess
from datetime import UTC, datetime, timedelta
from pathlib import Path

import pytest

from tests.support.cli_runner import one_error_line, run_cli
from tests.support.rows import stored_names
from tests.support.synthetic import TOUCH_ARFF, write
from touchbench.app.schemas.datasets import ImportRequest
from touchbench.app.services import datasets as dataset_service
from touchbench.app.services.listing import list_datasets
from touchbench.app.store import datasets as store_datasets
from touchbench.app.store.database import Store
from touchbench.app.store.tables import RunRow
from touchbench.benchmark.errors import DataFormatError
from touchbench.benchmark.io.arff import read_arff

# ------------------------------------------------------------------------------- names


def test_the_readme_walk_through_works_by_the_file_name(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    mini = write(tmp_path, "mini.arff", TOUCH_ARFF)
    imported = run_cli(capsys, store_url, "import", str(mini), "--json")
    assert imported.code == 0, imported.err
    assert imported.json()["name"] == "mini" and imported.json()["action"] == "imported"
    shown = run_cli(capsys, store_url, "show", "mini", "--json").json()
    assert shown["relation"] == "touch: -C 2"
    refused = run_cli(capsys, store_url, "export", "mini", "-o", str(mini))
    one_error_line(refused, "exists", "--force")
    assert mini.read_text(encoding="utf-8") == TOUCH_ARFF
    replaced = run_cli(capsys, store_url, "export", "mini", "-o", str(mini), "--force")
    assert replaced.code == 0, replaced.err
    assert mini.read_text(encoding="utf-8").startswith("@relation 'touch: -C 2'\n")
    assert read_arff(mini).equals(read_arff(write(tmp_path, "original.arff", TOUCH_ARFF)))
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []


def test_known_content_under_another_name_or_targets_is_refused_saying_how(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    path = write(tmp_path, "mini.arff", TOUCH_ARFF)
    first = run_cli(capsys, store_url, "import", str(path), "--json").json()
    again = run_cli(capsys, store_url, "import", str(path), "--json")
    assert again.code == 0 and again.json()["created"] is False
    assert again.json()["action"] == "already stored" and again.json()["id"] == first["id"]
    named = run_cli(capsys, store_url, "import", str(path), "--name", "mini", "--json")
    assert named.code == 0 and (named.json()["created"], named.json()["id"]) == (False, first["id"])
    renamed = run_cli(capsys, store_url, "import", str(path), "--name", "robot1")
    one_error_line(
        renamed, "already stored as dataset 1 'mini'", "renaming dataset 1 gives it that name"
    )
    retargeted = run_cli(capsys, store_url, "import", str(path), "--targets", "-1")
    one_error_line(
        retargeted, "already stored", "targets gesture, place", "a run chooses its own targets"
    )
    assert stored_names(capsys, store_url) == ["mini"]


def test_rename_then_every_command_finds_the_new_name(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    run_cli(capsys, store_url, "import", str(write(tmp_path, "mini.arff", TOUCH_ARFF)))
    other = write(tmp_path, "other.arff", TOUCH_ARFF.replace("0.5", "0.25"))
    run_cli(capsys, store_url, "import", str(other))
    renamed = run_cli(capsys, store_url, "rename", "mini", "robot1")
    assert renamed.code == 0 and "'mini' to 'robot1'" in renamed.err
    assert stored_names(capsys, store_url) == ["robot1", "other"]
    assert run_cli(capsys, store_url, "show", "robot1").code == 0
    one_error_line(run_cli(capsys, store_url, "rename", "robot1", "other"), "already exists")
    one_error_line(run_cli(capsys, store_url, "rename", "robot1", "42"), "cannot be a number")
    one_error_line(run_cli(capsys, store_url, "rename", "nope", "x"), "no dataset 'nope'")
    assert stored_names(capsys, store_url) == ["robot1", "other"]


@pytest.mark.parametrize(
    ("name", "expected"),
    [
        ("x" * 201, "at most 200 characters"),
        ("bad\x1b[31mname", "control characters"),
        ("tab\tname", "control characters"),
        ("", "cannot be empty"),
        (" padded", "start or end with spaces"),
        ("007", "cannot be a number"),
    ],
)
def test_invalid_names_are_refused_at_import_and_rename(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path, name: str, expected: str
) -> None:
    path = write(tmp_path, "mini.arff", TOUCH_ARFF)
    one_error_line(run_cli(capsys, store_url, "import", str(path), "--name", name), expected)
    assert stored_names(capsys, store_url) == []
    assert run_cli(capsys, store_url, "import", str(path)).code == 0
    one_error_line(run_cli(capsys, store_url, "rename", "mini", name), expected)
    assert stored_names(capsys, store_url) == ["mini"]


def test_a_name_of_200_characters_is_kept_and_tables_stay_narrow(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    long_name = "n" * 200
    path = write(tmp_path, "mini.arff", TOUCH_ARFF)
    assert run_cli(capsys, store_url, "import", str(path), "--name", long_name).code == 0
    run_cli(capsys, store_url, "import", str(write(tmp_path, "b.arff", TOUCH_ARFF + "\n% b\n")))
    assert stored_names(capsys, store_url) == [long_name, "b"]
    listing = run_cli(capsys, store_url, "datasets")
    assert listing.code == 0
    assert max(len(line) for line in listing.out.splitlines()) <= 160
    assert long_name not in listing.out and "…" in listing.out


def test_no_dataset_errors_list_a_few_short_names(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    for i in range(12):
        path = write(tmp_path, f"{'long' * 20}{i:02d}.arff", TOUCH_ARFF + f"\n% {i}\n")
        assert run_cli(capsys, store_url, "import", str(path)).code == 0
    line = one_error_line(run_cli(capsys, store_url, "show", "nope" * 300), "no dataset")
    assert "(12 in all)" in line
    assert len(line) < 700
    assert "longlong" in line and "long" * 20 not in line


# ------------------------------------------------------------------------- bounded input


def test_devices_pipes_and_binary_files_are_refused_at_once(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    one_error_line(run_cli(capsys, store_url, "import", "/dev/zero"), "not a regular file")
    fifo = tmp_path / "pipe.arff"
    os.mkfifo(fifo)
    one_error_line(run_cli(capsys, store_url, "import", str(fifo)), "not a regular file")
    wav = tmp_path / "touch.wav"
    wav.write_bytes(b"RIFF\x24\x08\x00\x00WAVEfmt \x10\x00\x00\x00" + bytes(4096))
    one_error_line(
        run_cli(capsys, store_url, "import", str(wav), "--format", "arff"), "not a text file"
    )
    one_error_line(
        run_cli(capsys, store_url, "import", str(wav), "--format", "csv"), "not a text file"
    )
    one_error_line(run_cli(capsys, store_url, "import", str(tmp_path)), "is a directory")
    assert stored_names(capsys, store_url) == []


# ------------------------------------------------------------------------ ordinary errors


def test_export_errors_are_one_line_and_leave_nothing_behind(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    files = tmp_path / "files"
    files.mkdir()
    run_cli(capsys, store_url, "import", str(write(files, "mini.arff", TOUCH_ARFF)))
    missing = files / "no" / "such" / "out.arff"
    one_error_line(
        run_cli(capsys, store_url, "export", "mini", "-o", str(missing)), "does not exist"
    )
    one_error_line(run_cli(capsys, store_url, "export", "mini", "-o", str(files)), "folder")
    one_error_line(run_cli(capsys, store_url, "export", "mini", "-o", "/dev/full"), "No space left")
    assert run_cli(capsys, store_url, "export", "mini", "-o", "/dev/null").code == 0
    one_error_line(run_cli(capsys, store_url, "export", "nope", "-o", str(files / "x")))
    assert sorted(p.name for p in files.iterdir()) == ["mini.arff"]


def test_an_export_that_fails_midway_keeps_the_old_file(
    capsys: pytest.CaptureFixture[str],
    store_url: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    files = tmp_path / "files"
    files.mkdir()
    run_cli(capsys, store_url, "import", str(write(files, "mini.arff", TOUCH_ARFF)))
    target = write(files, "out.arff", "precious\n")
    monkeypatch.setattr(store_datasets, "READ_BATCH", 1)
    real = dataset_service.ArffWriter.write_block
    calls = {"n": 0}

    def failing(self: dataset_service.ArffWriter, *args: object) -> None:
        calls["n"] += 1
        if calls["n"] == 3:
            raise OSError(28, "No space left on device")
        real(self, *args)  # type: ignore[arg-type]

    monkeypatch.setattr(dataset_service.ArffWriter, "write_block", failing)
    result = run_cli(capsys, store_url, "export", "mini", "-o", str(target), "--force")
    one_error_line(result, "cannot write", "No space left on device")
    assert target.read_text(encoding="utf-8") == "precious\n"
    assert sorted(p.name for p in files.iterdir()) == ["mini.arff", "out.arff"]


def _add_run(
    store_url: str, status: str, heartbeat: datetime | None, owner: str | None = None
) -> int:
    store = Store(store_url)
    with store.session() as session:
        run = RunRow(
            dataset_id=1,
            kind="multi-class",
            targets=["gesture"],
            classifiers=["zeror"],
            config={},
            status=status,
            heartbeat_at=heartbeat,
            owner=owner,
        )
        session.add(run)
        session.flush()
        run_id = run.id
    store.dispose()
    return run_id


#: A process on another machine (judged by its heartbeat), this test's own process (alive),
#: and a process of this machine that has ended.
ELSEWHERE, HERE, GONE = "elsewhere.example:4242@1", "here", "gone"


@pytest.mark.parametrize(
    ("status", "owner", "age", "refused"),
    [
        ("running", ELSEWHERE, timedelta(seconds=5), True),
        ("running", HERE, timedelta(minutes=5), True),
        ("queued", None, None, True),
        ("queued", None, timedelta(seconds=10), True),
        ("running", ELSEWHERE, timedelta(minutes=5), False),
        ("running", GONE, timedelta(seconds=1), False),
        ("running", None, None, False),
        ("done", None, timedelta(seconds=1), False),
    ],
)
def test_delete_is_refused_while_a_live_run_uses_the_dataset(
    capsys: pytest.CaptureFixture[str],
    store_url: str,
    tmp_path: Path,
    status: str,
    owner: str | None,
    age: timedelta | None,
    refused: bool,
) -> None:
    from touchbench.app.store.ownership import process_owner

    imported = run_cli(capsys, store_url, "import", str(write(tmp_path, "mini.arff", TOUCH_ARFF)))
    assert imported.code == 0
    heartbeat = None if age is None else datetime.now(UTC) - age
    if owner == HERE:
        owner = process_owner()
    elif owner == GONE:
        ended = subprocess.run(["true"], check=True)
        owner = process_owner(pid=2**22 + ended.returncode)  # a pid no process has here
    run_id = _add_run(store_url, status, heartbeat, owner)
    result = run_cli(capsys, store_url, "delete", "mini")
    if refused:
        one_error_line(result, f"in use by run {run_id}", f"cancel run {run_id} first")
        assert stored_names(capsys, store_url) == ["mini"]
    else:
        assert result.code == 0, result.err
        assert stored_names(capsys, store_url) == []


# ----------------------------------------------------------------------- silent changes


@pytest.mark.parametrize(
    ("name", "content", "expected"),
    [
        (
            "header.arff",
            "@relation r\n@attribute a numeric\n@attribute c {x,y}\n@data\n% nothing\n",
            "no instances",
        ),
        ("header.csv", "a,b,c\n", "no instances"),
        (
            "inf.arff",
            "@relation r\n@attribute a numeric\n@attribute c {x,y}\n@data\n1,x\n1e309,y\n",
            "inf.arff:6: attribute 'a': infinity",
        ),
        (
            "neginf.arff",
            "@relation r\n@attribute a numeric\n@attribute c {x,y}\n@data\n-Infinity,x\n",
            "attribute 'a': -infinity",
        ),
        ("inf.csv", "a,c\n1,x\ninf,y\n", "attribute 'a': infinity (data row 2)"),
        ("alone.arff", "@relation r\n@attribute c {x,y}\n@data\nx\n", "no features"),
    ],
)
def test_data_that_would_fail_later_is_refused_at_import(
    capsys: pytest.CaptureFixture[str],
    store_url: str,
    tmp_path: Path,
    name: str,
    content: str,
    expected: str,
) -> None:
    result = run_cli(capsys, store_url, "import", str(write(tmp_path, name, content)))
    one_error_line(result, expected)
    assert stored_names(capsys, store_url) == []


def test_a_numeric_target_is_imported_with_a_note_and_shown_as_regression(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    path = write(
        tmp_path,
        "force.arff",
        "@relation r\n@attribute a numeric\n@attribute y numeric\n@data\n1,2.5\n",
    )
    imported = run_cli(capsys, store_url, "import", str(path))
    assert imported.code == 0
    assert "note: target 'y' is numeric: a regression target" in imported.err
    as_json = run_cli(capsys, store_url, "show", "force", "--json").json()
    assert any("regression" in note for note in as_json["notes"])
    shown = run_cli(capsys, store_url, "show", "force")
    assert "regression" in shown.err


def test_a_stray_word_among_numbers_is_reported_where_it_is(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    rows = [f"{i / 10},{'tap' if i % 2 else 'slap'}" for i in range(20)]
    rows[13] = "oops,tap"
    path = write(tmp_path, "touches.csv", "energy,gesture\n" + "\n".join(rows) + "\n")
    imported = run_cli(capsys, store_url, "import", str(path), "--json")
    assert imported.code == 0
    (note,) = imported.json()["notes"]
    assert "column 'energy' is nominal because of 'oops' (line 15)" in note
    assert "19 cells are numbers" in note
    printed = run_cli(capsys, store_url, "import", str(path))
    assert re.search(r"note: .*column 'energy' is nominal", printed.err)


# -------------------------------------------------------------------------------- help


def test_help_shows_plain_metavars_and_the_rename_command(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    db = f"sqlite:///{tmp_path / 'help.db'}"
    for command, metavars in (
        ("import", ["FILE", "NAME", "N|NAMES"]),
        ("export", ["DATASET", "FILE"]),
        ("rename", ["DATASET", "NEW"]),
    ):
        result = run_cli(capsys, db, command, "--help")
        assert result.code == 0
        for metavar in metavars:
            assert metavar in result.out
        assert "{file}" not in result.out and "--json             <bool>" not in result.out
        json_line = [line for line in result.out.splitlines() if "--json" in line]
        assert all("<bool>" not in line for line in json_line)
    listing = run_cli(capsys, db, "--help")
    assert "rename" in listing.out


def test_an_upload_is_named_and_reported_by_its_own_file_name(
    store_url: str, tmp_path: Path
) -> None:
    store = Store(store_url)
    temporary = write(tmp_path, "upload-1a2b3c.tmp", TOUCH_ARFF)
    result = dataset_service.import_file(
        store, ImportRequest(file=temporary, source_name="robot arm.arff")
    )
    assert (result.name, result.created) == ("robot_arm", True)
    assert list_datasets(store)[0].source == "robot arm.arff"
    broken = write(tmp_path, "upload-4d5e6f.tmp", TOUCH_ARFF.replace("0.75", "oops"))
    with pytest.raises(DataFormatError) as caught:
        dataset_service.import_file(store, ImportRequest(file=broken, source_name="bad.arff"))
    assert str(caught.value).startswith("bad.arff:12: attribute 'energy'")
    csv = write(tmp_path, "upload-7a8b9c.tmp", "a,b\n1,x\n2,y,3\n")
    with pytest.raises(DataFormatError, match=r"^bad\.csv:3: "):
        dataset_service.import_file(store, ImportRequest(file=csv, source_name="bad.csv"))
    store.dispose()
