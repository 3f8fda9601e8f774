"""Columns set aside on reading (benchmark.io.columns): a group column becomes the instances'
groups and ignored columns are dropped, in CSV and ARFF alike, and neither reaches the
features; choices that do not fit the file are refused naming the column."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests.support.grasp_table import FEATURES, OBJECTS, grasp_arff, grasp_csv, grasp_rows
from touchbench.benchmark.dataset import Dataset, Schema
from touchbench.benchmark.errors import DataFormatError
from touchbench.benchmark.io.arff import open_arff, read_arff
from touchbench.benchmark.io.columns import ColumnChoice, ColumnError
from touchbench.benchmark.io.csv import read_csv
from touchbench.benchmark.problem import problem_from_dataset
from touchbench.benchmark.run.folds import make_fold_plan

GROUPED = ColumnChoice(groups="object", ignore=("trial",))


def expected_values(objects: int = 8, grasps: int = 10) -> np.ndarray:
    rows = grasp_rows(objects=objects, grasps=grasps)
    return np.array(
        [[*(round(v, 5) for v in values), slipped == "yes"] for *_, values, slipped in rows]
    )


def check_grouped(dataset: Dataset) -> None:
    """Six features and the label; the object only as the groups, the trial nowhere."""
    schema = dataset.schema
    assert schema.feature_names == FEATURES and schema.target_names == ("slipped",)
    assert [a.name for a in schema.attributes] == [*FEATURES, "slipped"]
    assert schema.group_column == "object"
    assert dataset.X.shape == (80, 6)
    assert dataset.groups is not None
    assert dataset.groups.tolist() == [name for name in OBJECTS for _ in range(10)]
    np.testing.assert_allclose(dataset.values[:, :6], expected_values()[:, :6], atol=1e-12)
    codes = [dataset.schema.targets[0].values[int(c)] for c in dataset.Y[:, 0]]
    assert codes == [slipped for *_, slipped in grasp_rows()]


def test_a_csv_group_column_becomes_the_groups_and_ignored_columns_are_gone(
    tmp_path: Path,
) -> None:
    dataset = read_csv(grasp_csv(tmp_path / "grasps.csv"), columns=GROUPED)
    check_grouped(dataset)
    plain = read_csv(grasp_csv(tmp_path / "grasps.csv"))
    assert plain.groups is None and plain.schema.group_column is None
    assert plain.schema.feature_names[:2] == ("object", "trial")  # what --groups prevents


@pytest.mark.parametrize("parser", ["tokenizer", "vectorised"])
def test_an_arff_group_attribute_becomes_the_groups_whichever_way_rows_are_read(
    tmp_path: Path, parser: str
) -> None:
    dataset = read_arff(grasp_arff(tmp_path / "grasps.arff"), columns=GROUPED, parser=parser)  # type: ignore[arg-type]
    check_grouped(dataset)


@pytest.mark.parametrize(("kind", "first"), [("string", "mug"), ("numeric", "1")])
def test_string_and_numeric_group_attributes_give_their_text_block_after_block(
    tmp_path: Path, kind: str, first: str
) -> None:
    path = grasp_arff(tmp_path / "grasps.arff", kind=kind)
    with open_arff(path, columns=ColumnChoice(groups="object"), block_bytes=512) as reader:
        blocks = list(reader.blocks())
        schema = reader.schema
    assert len(blocks) > 5  # the string table grew while blocks were handed on
    groups = np.concatenate([block.groups for block in blocks if block.groups is not None])
    assert groups.size == 80 and groups[0] == first
    expected = [str(i + 1) if kind == "numeric" else name for i, name in enumerate(OBJECTS)]
    assert list(dict.fromkeys(groups.tolist())) == expected
    assert "object" not in [a.name for a in schema.attributes]
    assert schema.feature_names == ("trial", *FEATURES)
    assert all(block.values.shape[1] == 8 for block in blocks)


def test_the_schema_keeps_its_group_column_through_json() -> None:
    schema = Schema("r", (), (), group_column="subject")
    assert Schema.from_json(schema.to_json()) == schema
    assert "group_column" not in Schema("r", (), ()).to_json()


def test_the_plan_sets_columns_aside_in_a_data_set_held_in_memory(tmp_path: Path) -> None:
    plain = read_csv(grasp_csv(tmp_path / "grasps.csv"), targets=["slipped"])
    from touchbench.benchmark.io.columns import plan_columns

    names = [a.name for a in plain.schema.attributes]
    plan = plan_columns(names, plain.schema.target_indices, GROUPED, source="grasps")
    dataset = plan.dataset(plain, source="grasps")
    assert dataset.schema.feature_names == FEATURES
    assert dataset.groups is not None and dataset.groups[0] == "mug"


@pytest.mark.parametrize(
    ("choice", "targets", "field", "words"),
    [
        (ColumnChoice(groups="objekt"), None, "groups", "no column named 'objekt' in"),
        (ColumnChoice(ignore=("trail",)), None, "ignore", "no column named 'trail' in"),
        (ColumnChoice(groups="slipped"), None, "groups", "column 'slipped' of"),
        (ColumnChoice(groups="trial"), ["trial"], "groups", "column 'trial' of"),
        (ColumnChoice(groups="object", ignore=("object",)), None, "ignore", "column 'object' of"),
        (ColumnChoice(ignore=("slipped",)), None, "ignore", "column 'slipped' of"),
        (
            ColumnChoice(ignore=("object", "trial", *FEATURES, "slipped")),
            None,
            "ignore",
            "every column of",
        ),
        (
            ColumnChoice(groups="object", ignore=("trial", *FEATURES)),
            None,
            "ignore",
            "no feature is left",
        ),
    ],
)
def test_choices_that_do_not_fit_are_refused_naming_the_column(
    tmp_path: Path,
    choice: ColumnChoice,
    targets: list[str] | None,
    field: str,
    words: str,
) -> None:
    for path, read in (
        (grasp_csv(tmp_path / "grasps.csv"), read_csv),
        (grasp_arff(tmp_path / "grasps.arff"), read_arff),
    ):
        with pytest.raises(ColumnError) as refused:
            read(path, targets=targets, columns=choice)  # type: ignore[operator]
        assert refused.value.field == field
        message = str(refused.value)
        assert words in message and str(path) in message and "\n" not in message


def test_the_default_target_is_said_to_be_one_when_the_group_column_is_it(
    tmp_path: Path,
) -> None:
    with pytest.raises(ColumnError, match=r"a target \(the last column, by default\)"):
        read_csv(grasp_csv(tmp_path / "grasps.csv"), columns=ColumnChoice(groups="slipped"))
    with pytest.raises(ColumnError, match=r"a target \(the last attribute, by default\)"):
        read_arff(grasp_arff(tmp_path / "grasps.arff"), columns=ColumnChoice(groups="slipped"))


def test_a_row_without_a_group_is_refused_with_its_line(tmp_path: Path) -> None:
    path = grasp_csv(tmp_path / "grasps.csv", missing_group_at=41)
    with pytest.raises(DataFormatError) as refused:
        read_csv(path, columns=GROUPED)
    assert (refused.value.line, refused.value.attribute) == (43, "object")
    arff = tmp_path / "grasps.arff"
    text = grasp_arff(arff).read_text().splitlines()
    text[12 + 41] = "?" + text[12 + 41][text[12 + 41].index(",") :]
    arff.write_text("\n".join(text) + "\n")
    with pytest.raises(DataFormatError) as refused:
        read_arff(arff, columns=GROUPED)
    assert (refused.value.line, refused.value.attribute) == (54, "object")
    assert "no group" in str(refused.value)


def test_group_k_fold_keeps_each_object_on_one_side(tmp_path: Path) -> None:
    problem, _ = problem_from_dataset(read_csv(grasp_csv(tmp_path / "grasps.csv"), columns=GROUPED))
    assert problem.groups is not None
    plan = make_fold_plan(problem.Y, n_folds=4, groups=problem.groups, seed=3)
    assert plan.scheme == "stratified group k-fold" and len(plan.folds) == 4
    for fold in plan.folds:
        assert not set(problem.groups[fold.train]) & set(problem.groups[fold.test])


def test_leave_one_group_out_tests_each_object_once(tmp_path: Path) -> None:
    problem, _ = problem_from_dataset(read_csv(grasp_csv(tmp_path / "grasps.csv"), columns=GROUPED))
    assert problem.groups is not None
    plan = make_fold_plan(problem.Y, groups=problem.groups, split="leave-one-group-out")
    assert len(plan.folds) == 8 and plan.scheme == "leave-one-group-out over 8 groups"
    assert plan.test_groups == tuple(sorted(OBJECTS))
    for fold, held_out in zip(plan.folds, plan.test_groups, strict=True):
        assert set(problem.groups[fold.test]) == {held_out}
        assert held_out not in set(problem.groups[fold.train])
        assert fold.train.size + fold.test.size == 80
