"""Tables from other labs on the command line: `import --groups COLUMN --ignore COLUMNS` stores
the group column as the instances' groups and leaves ignored columns out, `show` says so,
and choices that do not fit the file are refused in one line with nothing stored, on SQLite;
a refusal after blocks were written, and an import found again, on SQLite and PostgreSQL."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from sqlalchemy import func, select

from tests.support.cli_runner import one_error_line, run_cli
from tests.support.grasp_table import FEATURES, OBJECTS, grasp_arff, grasp_csv
from tests.support.rows import stored_names
from touchbench.app.services.datasets import describe_dataset
from touchbench.app.store import datasets as stored
from touchbench.app.store.database import Store
from touchbench.app.store.tables import DatasetRow, InstanceBlockRow, InstanceRow
from touchbench.benchmark.dataset import Attribute, Dataset, Schema
from touchbench.benchmark.io.textfile import BLOCK_BYTES
from touchbench.benchmark.problem import problem_from_dataset
from touchbench.benchmark.run.folds import make_fold_plan


def rows_in_store(store_url: str) -> tuple[int, int, int]:
    """Rows of ``datasets``, ``instance_blocks`` and ``instances``."""
    store = Store(store_url)
    try:
        with store.session() as session:
            return tuple(  # type: ignore[return-value]
                int(session.scalar(select(func.count()).select_from(table)) or 0)
                for table in (DatasetRow, InstanceBlockRow, InstanceRow)
            )
    finally:
        store.dispose()


def load(store_url: str, name: str) -> Dataset:
    store = Store(store_url)
    try:
        return stored.load_dataset(store, name)
    finally:
        store.dispose()


def test_the_group_column_is_stored_as_groups_and_ignored_columns_are_left_out(
    capsys: pytest.CaptureFixture[str], sqlite_store_url: str, tmp_path: Path
) -> None:
    path = grasp_csv(tmp_path / "grasps.csv")
    imported = run_cli(
        capsys,
        sqlite_store_url,
        "import",
        str(path),
        "--groups",
        "object",
        "--ignore",
        "trial",
        "--json",
    )
    assert imported.code == 0, imported.err
    result = imported.json()
    assert (result["n_instances"], result["n_features"], result["targets"]) == (80, 6, ["slipped"])
    assert result["groups"] == {"count": 8, "column": "object"}
    assert "columns left out: trial" in result["notes"]

    shown = run_cli(capsys, sqlite_store_url, "show", "grasps", "--json").json()
    assert shown["groups"] == {"count": 8, "column": "object"}
    assert [a["name"] for a in shown["attributes"]] == [*FEATURES, "slipped"]
    text = run_cli(capsys, sqlite_store_url, "show", "grasps")
    assert text.code == 0 and "groups: 8, from column 'object'" in text.err

    dataset = load(sqlite_store_url, "grasps")
    assert dataset.schema.feature_names == FEATURES
    assert dataset.schema.group_column == "object"
    assert dataset.groups is not None
    assert dataset.groups.tolist() == [name for name in OBJECTS for _ in range(10)]

    problem, _ = problem_from_dataset(dataset)
    assert problem.X.shape == (80, 6) and problem.groups is not None
    for plan in (
        make_fold_plan(problem.Y, n_folds=5, groups=problem.groups, seed=2),
        make_fold_plan(problem.Y, groups=problem.groups, split="leave-one-group-out"),
    ):
        for fold in plan.folds:
            assert not set(problem.groups[fold.train]) & set(problem.groups[fold.test])
    logo = make_fold_plan(problem.Y, groups=problem.groups, split="leave-one-group-out")
    assert len(logo.folds) == 8 and logo.scheme == "leave-one-group-out over 8 groups"


def test_an_arff_group_attribute_is_stored_as_groups(
    capsys: pytest.CaptureFixture[str], sqlite_store_url: str, tmp_path: Path
) -> None:
    path = grasp_arff(tmp_path / "grasps.arff", kind="string")
    imported = run_cli(
        capsys, sqlite_store_url, "import", str(path), "--groups", "object", "--ignore", "trial"
    )
    assert imported.code == 0, imported.err
    assert "groups: 8, from column 'object'" in imported.err
    dataset = load(sqlite_store_url, "grasps")
    assert dataset.schema.feature_names == FEATURES
    assert dataset.groups is not None and set(dataset.groups.tolist()) == set(OBJECTS)


def test_other_columns_set_aside_make_another_data_set(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    path = grasp_csv(tmp_path / "grasps.csv")
    plain = run_cli(capsys, store_url, "import", str(path), "--json").json()
    assert plain["n_features"] == 8 and plain["groups"] is None
    grouped = run_cli(
        capsys, store_url, "import", str(path), "--groups", "object", "--ignore", "trial", "--json"
    ).json()
    assert grouped["created"] is True and grouped["id"] != plain["id"]
    again = run_cli(
        capsys, store_url, "import", str(path), "--ignore", "trial", "--groups", "object", "--json"
    ).json()
    assert again["created"] is False and again["id"] == grouped["id"]
    assert again["groups"] == {"count": 8, "column": "object"}
    assert stored_names(capsys, store_url) == ["grasps", "grasps-2"]


@pytest.mark.parametrize(
    ("options", "expected"),
    [
        (["--groups", "objekt"], ["--groups: no column named 'objekt' in", "grasps.csv"]),
        (["--ignore", "trial,trail"], ["--ignore: no column named 'trail' in", "grasps.csv"]),
        (["--groups", "slipped"], ["--groups: column 'slipped' of", "is a target"]),
        (
            ["--groups", "object", "--targets", "object"],
            ["--groups: column 'object' of", "is a target"],
        ),
        (
            ["--groups", "object", "--ignore", "trial,object"],
            ["--ignore: column 'object' of", "names the groups"],
        ),
        (["--ignore", "slipped"], ["--ignore: column 'slipped' of", "a target cannot be ignored"]),
        (
            ["--ignore", ",".join(["object", "trial", *FEATURES, "slipped"])],
            ["--ignore: every column of", "is ignored"],
        ),
        (
            ["--groups", "object", "--ignore", ",".join(["trial", *FEATURES])],
            ["--ignore: no feature is left in"],
        ),
        (["--groups", ""], ["--groups:"]),
    ],
)
def test_column_choices_that_do_not_fit_are_one_line_and_store_nothing(
    capsys: pytest.CaptureFixture[str],
    sqlite_store_url: str,
    tmp_path: Path,
    options: list[str],
    expected: list[str],
) -> None:
    path = grasp_csv(tmp_path / "grasps.csv")
    one_error_line(run_cli(capsys, sqlite_store_url, "import", str(path), *options), *expected)
    arff = grasp_arff(tmp_path / "grasps.arff")
    words = [text.replace("grasps.csv", "grasps.arff") for text in expected]
    one_error_line(run_cli(capsys, sqlite_store_url, "import", str(arff), *options), *words)
    assert stored_names(capsys, sqlite_store_url) == []
    assert rows_in_store(sqlite_store_url) == (0, 0, 0)


def test_an_instance_without_a_group_far_into_a_large_file_stores_nothing(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    """The file streams into the store block by block: the refusal comes after blocks were
    written, inside the import's transaction, which leaves nothing behind."""
    path = tmp_path / "grasps.arff"
    rng = np.random.default_rng(0)
    n = 90_000
    values = rng.normal(size=(n, len(FEATURES)))
    objects = np.array(OBJECTS)[np.arange(n) % len(OBJECTS)].astype(object)
    objects[n - 10] = "?"
    with path.open("w", encoding="utf-8") as out:
        out.write("@relation grasps\n@attribute object {" + ",".join(OBJECTS) + "}\n")
        out.write("".join(f"@attribute {name} numeric\n" for name in FEATURES))
        out.write("@attribute slipped {no,yes}\n@data\n")
        for i in range(n):
            cells = ",".join(f"{v:.6f}" for v in values[i])
            out.write(f"{objects[i]},{cells},{'yes' if i % 3 else 'no'}\n")
    assert path.stat().st_size > BLOCK_BYTES + (1 << 20)  # more than one block of the reader
    refused = run_cli(capsys, store_url, "import", str(path), "--groups", "object")
    line = one_error_line(refused, "grasps.arff", "attribute 'object'", "no group")
    assert f":{10 + (n - 10) + 1}:" in line  # the header's 10 lines, then the data rows
    assert stored_names(capsys, store_url) == []
    assert rows_in_store(store_url) == (0, 0, 0)


def test_an_extracted_data_set_says_its_groups_are_the_recordings(sqlite_store_url: str) -> None:
    schema = Schema(
        "touch: -C 1",
        (Attribute("gesture", "nominal", ("tap", "slap")), Attribute("rms", "numeric")),
        (0,),
    )
    dataset = Dataset(
        schema,
        np.array([[0, 0.1], [1, 0.2], [0, 0.3], [1, 0.4]]),
        groups=np.array(["a.wav", "a.wav", "b.wav", "c.wav"], dtype=object),
    )
    store = Store(sqlite_store_url)
    try:
        stored.add_dataset(store, dataset, sha256="0" * 64, name="touch")
        groups = describe_dataset(store, "touch").groups
    finally:
        store.dispose()
    assert groups is not None and (groups.count, groups.column) == (3, None)


def test_group_names_are_kept_to_the_letter(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    names = ["tab\there", 'quote " and, comma', "naïve café", "back\\slash", "line\nbreak", "01"]
    path = tmp_path / "odd.csv"
    lines = ["who,x,y"]
    for i in range(24):
        name = names[i % len(names)].replace('"', '""')
        lines.append(f'"{name}",{i * 0.5},{"ab"[i % 2]}')
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    imported = run_cli(capsys, store_url, "import", str(path), "--groups", "who", "--json")
    assert imported.code == 0, imported.err
    assert imported.json()["groups"] == {"count": 6, "column": "who"}
    dataset = load(store_url, "odd")
    assert dataset.groups is not None
    assert dataset.groups.tolist() == [names[i % len(names)] for i in range(24)]
