"""Tests of benchmark.io.csv: reading CSV files into datasets."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from touchbench.benchmark.dataset import Attribute
from touchbench.benchmark.errors import DataFormatError
from touchbench.benchmark.io.csv import read_csv, sniff_delimiter

NAN = np.nan


def write(tmp_path: Path, text: str, name: str = "touches.csv", encoding: str = "utf-8") -> Path:
    path = tmp_path / name
    path.write_bytes(text.encode(encoding))
    return path


@pytest.mark.parametrize("delimiter", [",", ";", "\t"])
def test_delimiter_is_sniffed(tmp_path: Path, delimiter: str) -> None:
    text = "\n".join(delimiter.join(row) for row in [["a", "b", "label"], ["1", "2.5", "tap"]])
    dataset = read_csv(write(tmp_path, text + "\n"))
    assert [a.name for a in dataset.schema.attributes] == ["a", "b", "label"]
    np.testing.assert_array_equal(dataset.values, [[1, 2.5, 0]])


def test_sniffing_prefers_the_delimiter_that_splits_every_line_alike() -> None:
    # Decimal commas: every line has 2 ';'-separated cells, commas vary.
    assert sniff_delimiter("x;y\n1,5;a\n2;b\n3,25;c\n") == ";"
    assert sniff_delimiter("single\n1\n2\n") == ","


def test_columns_are_typed_and_nominal_labels_keep_first_appearance(tmp_path: Path) -> None:
    dataset = read_csv(
        write(tmp_path, "force,place,gesture\n0.5,head,tap\n-2e3,arm,slap\n7,head,tap\n")
    )
    force, place, gesture = dataset.schema.attributes
    assert force == Attribute("force", "numeric", (), "numeric")
    assert place == Attribute("place", "nominal", ("head", "arm"), "nominal")
    assert gesture.values == ("tap", "slap")
    np.testing.assert_array_equal(dataset.values, [[0.5, 0, 0], [-2000, 1, 1], [7, 0, 0]])
    assert dataset.schema.target_indices == (2,)
    assert dataset.schema.relation == "touches"


def test_missing_cells(tmp_path: Path) -> None:
    dataset = read_csv(write(tmp_path, "a,b,c\n,?,x\nNA,NaN,?\n 3 , 4 ,\n1,2,x\n"))
    np.testing.assert_array_equal(
        dataset.values, [[NAN, NAN, 0], [NAN, NAN, NAN], [3, 4, NAN], [1, 2, 0]]
    )
    assert dataset.schema.attributes[1].kind == "numeric"


def test_integer_target_becomes_nominal_sorted_by_value(tmp_path: Path) -> None:
    dataset = read_csv(write(tmp_path, "f,g,class\n1,5,10\n2,6,2\n3,7,-1\n4,8,2\n"))
    feature, other, target = dataset.schema.attributes
    assert feature.kind == "numeric" and other.kind == "numeric"
    assert target == Attribute("class", "nominal", ("-1", "2", "10"), "nominal")
    np.testing.assert_array_equal(dataset.Y[:, 0], [2, 1, 0, 1])


def test_non_integer_numeric_target_stays_numeric(tmp_path: Path) -> None:
    dataset = read_csv(write(tmp_path, "f,y\n1,0.5\n2,1\n"))
    assert dataset.schema.targets[0].kind == "numeric"


def test_rfc4180_quotes(tmp_path: Path) -> None:
    text = 'name,"note, with comma",label\n"a ""quoted"" word","two\nlines",x\nplain,1,"y"\n'
    dataset = read_csv(write(tmp_path, text))
    name, note, label = dataset.schema.attributes
    assert note.name == "note, with comma"
    assert name.values == ('a "quoted" word', "plain")
    assert note.values == ("two\nlines", "1")
    assert label.values == ("x", "y")


@pytest.mark.parametrize(
    ("targets", "expected"),
    [(None, (3,)), (2, (0, 1)), (-2, (2, 3)), (["c", "a"], (0, 2))],
)
def test_targets(
    tmp_path: Path, targets: int | list[str] | None, expected: tuple[int, ...]
) -> None:
    path = write(tmp_path, "a,b,c,d\nx,1,y,2\n")
    assert read_csv(path, targets=targets).schema.target_indices == expected


def test_relation_override_bom_latin1_crlf_and_blank_lines(tmp_path: Path) -> None:
    text = "\ufeffcaf\u00e9,label\r\n\r\n1,\u00e9t\u00e9\r\n2,hiver\r\n\r\n"
    utf8 = read_csv(write(tmp_path, text, "u.csv"), relation="r")
    latin1 = read_csv(write(tmp_path, text[1:], "l.csv", encoding="latin-1"), relation="r")
    assert utf8.schema.relation == "r"
    assert utf8.schema.attributes[0].name == "caf\u00e9"
    assert utf8.schema.attributes[1].values == ("\u00e9t\u00e9", "hiver")
    assert utf8.equals(latin1)


def _error(path: Path, **options: object) -> DataFormatError:
    with pytest.raises(DataFormatError) as caught:
        read_csv(path, **options)  # type: ignore[arg-type]
    assert caught.value.source == str(path)
    return caught.value


@pytest.mark.parametrize(
    ("text", "message", "line"),
    [
        ("", "empty file", None),
        ("\n \n", "empty file", None),
        ("1,2,3\n4,5,6\n", "no header", 1),
        ("a,b,a\n1,2,3\n", "duplicate column name", 1),
        ("a,,c\n1,2,3\n", "column 2 has no name", 1),
        ("a,b,c\n1,2,3\n4,5\n", "expected 3 columns (as in the header), found 2", 3),
        ("a,b,c\n1,2,3\n\n4,5,6,7\n", "expected 3 columns (as in the header), found 4", 4),
        ('a,b,c\n"x\ny",2,3\n4,5\n', "expected 3 columns (as in the header), found 2", 4),
        ('a,b\n"x"y,2\n', "malformed CSV", 2),
        ("only\n1\n", "at least one must remain a feature", 1),
    ],
)
def test_bad_files(tmp_path: Path, text: str, message: str, line: int | None) -> None:
    error = _error(write(tmp_path, text))
    assert message in error.message
    assert error.line == line


def test_duplicate_column_names_the_column(tmp_path: Path) -> None:
    assert _error(write(tmp_path, "a,b,a\n1,2,3\n")).attribute == "a"


def test_unknown_target_names(tmp_path: Path) -> None:
    error = _error(write(tmp_path, "a,b\n1,2\n"), targets=["zzz"])
    assert "no attribute named 'zzz'" in error.message
    assert error.line == 1


def test_missing_file(tmp_path: Path) -> None:
    assert "no such file" in _error(tmp_path / "absent.csv").message


def test_binary_file(tmp_path: Path) -> None:
    path = tmp_path / "garbage.csv"
    path.write_bytes(b"\x00\x9f\x12" * 50)
    assert "not a text file" in _error(path).message
