"""Tests of benchmark.io.arff: reading and writing WEKA ARFF."""

from __future__ import annotations

import io
import math
from datetime import UTC, datetime
from pathlib import Path

import numpy as np
import pytest

from tests.support.arff_texts import (
    CANONICAL,
    HEADER,
    MESSY,
    NAN,
    random_dataset,
)
from touchbench.benchmark.dataset import Attribute, Dataset, Schema
from touchbench.benchmark.errors import DataFormatError
from touchbench.benchmark.io.arff import dumps_arff, loads_arff, read_arff, write_arff
from touchbench.benchmark.io.dates import DateFormat


def epoch(
    year: int, month: int, day: int, hour: int = 0, minute: int = 0, second: int = 0, ms: int = 0
) -> float:
    """Seconds since the epoch of a UTC date-time, the oracle for date attributes."""
    return datetime(year, month, day, hour, minute, second, tzinfo=UTC).timestamp() + ms / 1000


def assert_values(dataset: Dataset, expected: list[list[float]]) -> None:
    np.testing.assert_array_equal(dataset.values, np.array(expected, dtype=float))


# ------------------------------------------------------------------------------- reading


def test_reads_a_dense_file_with_numeric_and_nominal_attributes() -> None:
    dataset = loads_arff(
        """@relation weather
@attribute outlook {sunny, overcast, rainy}
@attribute temperature real
@attribute humidity INTEGER
@attribute play {yes, no}
@data
sunny,85,85,no
overcast,83.5,86,yes
rainy,-1e-3,96,yes
"""
    )
    assert dataset.schema.relation == "weather"
    assert [a.name for a in dataset.schema.attributes] == [
        "outlook",
        "temperature",
        "humidity",
        "play",
    ]
    assert dataset.schema.attributes[0] == Attribute(
        "outlook", "nominal", ("sunny", "overcast", "rainy"), "nominal"
    )
    assert [a.declared_type for a in dataset.schema.attributes[1:3]] == ["real", "INTEGER"]
    assert dataset.schema.target_indices == (3,)
    assert_values(dataset, [[0, 85, 85, 1], [1, 83.5, 86, 0], [2, -0.001, 96, 0]])
    assert dataset.weights is None
    assert dataset.sparse is False


def test_keywords_are_case_insensitive_and_comments_and_blank_lines_are_skipped() -> None:
    dataset = loads_arff(
        """% a comment before everything

@RELATION r   % trailing comment
% another
@Attribute a NUMERIC
   @ATTRIBUTE b {x,y}% comment right after a brace

@DATA
% comment in the data
1,x   % trailing comment after a row

2,'y'
"""
    )
    assert_values(dataset, [[1, 0], [2, 1]])
    assert dataset.schema.attributes[0].declared_type == "NUMERIC"


def test_percent_inside_quotes_is_text_not_a_comment() -> None:
    dataset = loads_arff("@relation r\n@attribute s string\n@attribute c {a}\n@data\n'50% off',a\n")
    assert dataset.schema.attributes[0].values == ("50% off",)


def test_commas_and_whitespace_both_separate_values_as_in_weka() -> None:
    commas = loads_arff("@relation r\n@attribute a numeric\n@attribute b {x,y}\n@data\n1,y\n")
    spaces = loads_arff("@relation r\n@attribute a numeric\n@attribute b {x y}\n@data\n1 y\n")
    assert commas.equals(spaces)


def test_meka_multi_label_file_with_nominal_inputs_and_missing_values() -> None:
    dataset = loads_arff(
        """@relation 'scene: -C 3 -split 0.5'
@attribute beach {0,1}
@attribute sunset {0,1}
@attribute urban {0,1}
@attribute light {dark, dim, bright}
@attribute hue numeric
@data
1,0,?,bright,0.5
0,1,0,?,?
?,?,1,dim,2
"""
    )
    assert dataset.schema.relation == "scene: -C 3 -split 0.5"
    assert dataset.schema.target_names == ("beach", "sunset", "urban")
    assert dataset.schema.feature_names == ("light", "hue")
    np.testing.assert_array_equal(dataset.Y, [[1, 0, NAN], [0, 1, 0], [NAN, NAN, 1]])
    np.testing.assert_array_equal(dataset.X, [[2, 0.5], [NAN, NAN], [1, 2]])


@pytest.mark.parametrize(
    ("targets", "expected"),
    [(None, (1, 2, 3)), (1, (0,)), (-1, (3,)), (-2, (2, 3)), (["d", "b"], (1, 3))],
)
def test_targets_follow_meka_header_unless_overridden(
    targets: int | list[str] | None, expected: tuple[int, ...]
) -> None:
    text = (
        "@relation 'r: -C -3'\n@attribute a numeric\n@attribute b numeric\n"
        "@attribute c numeric\n@attribute d numeric\n@data\n1,2,3,4\n"
    )
    assert loads_arff(text, targets=targets).schema.target_indices == expected


def test_without_meka_option_the_last_attribute_is_the_target() -> None:
    text = "@relation plain\n@attribute a numeric\n@attribute b {u,v}\n@data\n1,u\n"
    assert loads_arff(text).schema.target_indices == (1,)


def test_sparse_rows_fill_unspecified_values_with_zero_and_keep_missing() -> None:
    dataset = loads_arff(
        """@relation sparse
@attribute a numeric
@attribute b numeric
@attribute c {first, second}
@attribute d numeric
@data
{1 2.5, 2 second}
{}
{0 ?, 3 -4}
{ 2 ?,3 7 }
"""
    )
    assert dataset.sparse is True
    assert_values(
        dataset,
        [[0, 2.5, 1, 0], [0, 0, 0, 0], [NAN, 0, 0, -4], [0, 0, NAN, 7]],
    )


def test_instance_weights_after_dense_and_sparse_rows() -> None:
    dense = loads_arff(
        "@relation w\n@attribute a numeric\n@attribute b {x,y}\n@data\n1,x,{0.5}\n2,y\n3,x, {2}\n"
    )
    np.testing.assert_array_equal(dense.weights, [0.5, 1, 2])
    sparse = loads_arff(
        "@relation w\n@attribute a numeric\n@attribute b {x,y}\n@data\n{0 1},{0.25}\n{1 y}\n"
    )
    np.testing.assert_array_equal(sparse.weights, [0.25, 1])
    assert_values(sparse, [[1, 0], [0, 1]])


def test_quotes_and_every_backslash_escape_are_decoded() -> None:
    dataset = loads_arff(
        r"""@relation 'it\'s a \"test\"'
@attribute 'name with spaces' {'a b', "c,d", 'q\'uote', "dq\"", 'back\\slash', '\%'}
@attribute "s" string
@data
'a b', 'tab\tnew\nret\r'
"c,d", "both ' and \" "
'q\'uote', 'octal \101\0619 and \q'
"dq\"", "bell\a back\b ff\f vt\v"
'back\\slash', x
'\%', '50\% \\n'
"""
    )
    assert dataset.schema.relation == 'it\'s a "test"'
    first, second = dataset.schema.attributes
    assert first.name == "name with spaces"
    assert first.values == ("a b", "c,d", "q'uote", 'dq"', "back\\slash", "%")
    assert second.values == (
        "tab\tnew\nret\r",
        "both ' and \" ",
        "octal A19 and q",
        "bell\a back\b ff\f vt\v",
        "x",
        "50% \\n",
    )
    assert_values(dataset, [[i, i] for i in range(6)])


def test_quoted_question_mark_is_a_value_and_bare_question_mark_is_missing() -> None:
    dataset = loads_arff(
        "@relation q\n@attribute a {'?', b}\n@attribute s string\n@data\n'?','?'\n?,?\nb,\"?\"\n"
    )
    assert dataset.schema.attributes[0].values == ("?", "b")
    assert dataset.schema.attributes[1].values == ("?",)
    assert_values(dataset, [[0, 0], [NAN, NAN], [1, 0]])


def test_string_attributes_keep_a_table_in_order_of_first_appearance() -> None:
    dataset = loads_arff(
        "@relation s\n@attribute text string\n@attribute c {y}\n@data\n"
        "hello,y\n'good bye',y\nhello,y\n?,y\n"
    )
    assert dataset.schema.attributes[0] == Attribute(
        "text", "string", ("hello", "good bye"), "string"
    )
    assert_values(dataset, [[0, 0], [1, 0], [0, 0], [NAN, 0]])


@pytest.mark.parametrize(
    ("declaration", "text", "expected"),
    [
        ("date", "2020-01-02T03:04:05", epoch(2020, 1, 2, 3, 4, 5)),
        ("DATE 'dd/MM/yyyy'", "29/02/2000", epoch(2000, 2, 29)),
        ("date 'dd/MM/yyyy'", "1/1/1970", 0.0),
        (
            'date "yyyy-MM-dd HH:mm:ss.SSS"',
            "'1999-12-31 23:59:59.250'",
            epoch(1999, 12, 31, 23, 59, 59, ms=250),
        ),
        ("date 'yyyy-MM-dd HH:mm:ss.S'", "'1970-01-01 00:00:00.5'", 0.005),
        ("date \"yyyy-MM-dd'T'HH:mm:ssZ\"", "2021-06-01T12:00:00+0200", epoch(2021, 6, 1, 10)),
        ("date \"yyyy-MM-dd'T'HH:mm:ssZ\"", "2021-06-01T12:00:00-0130", epoch(2021, 6, 1, 13, 30)),
        ("date \"yyyy-MM-dd'T'HH:mmXXX\"", "2021-06-01T12:00Z", epoch(2021, 6, 1, 12)),
        ("date \"yyyy-MM-dd'T'HH:mmXXX\"", "2021-06-01T12:00-05:00", epoch(2021, 6, 1, 17)),
        ("date \"yyyy-MM-dd'T'HH:mmX\"", "2021-06-01T12:00+03", epoch(2021, 6, 1, 9)),
        ("date \"d MMM yyyy 'at' H'h'\"", "'7 Mar 2015 at 9h'", epoch(2015, 3, 7, 9)),
        ('date "d MMMM yyyy"', "'12 december 1969'", epoch(1969, 12, 12)),
        ("date yyyyMMddHHmm", "190001010000", epoch(1900, 1, 1)),
        ("date \"HH 'o''clock'\"", '"13 o\'clock"', 13 * 3600.0),
        ("date", "?", NAN),
    ],
)
def test_dates_are_read_as_utc_epoch_seconds(declaration: str, text: str, expected: float) -> None:
    dataset = loads_arff(
        f"@relation r\n@attribute d {declaration}\n@attribute c {{k}}\n@data\n{text},k\n"
    )
    np.testing.assert_array_equal(dataset.values[:, 0], [expected])


def test_date_attributes_keep_their_declaration() -> None:
    dataset = loads_arff(
        "@relation r\n@attribute a date\n@attribute b DATE 'dd/MM/yyyy'\n@attribute c {k}\n@data\n"
    )
    default, custom = dataset.schema.attributes[:2]
    assert default == Attribute("a", "date", (), "date", None)
    assert custom == Attribute("b", "date", (), "DATE", "dd/MM/yyyy")


def test_date_format_writes_what_it_reads() -> None:
    pattern = DateFormat("yyyy.MM.dd 'o''clock' HH:mm:ss.SSS X")
    seconds = epoch(2024, 2, 29, 13, 5, 9, ms=7)
    assert pattern.format(seconds) == "2024.02.29 o'clock 13:05:09.007 Z"
    assert pattern.parse(pattern.format(seconds)) == seconds
    assert DateFormat("yyyy-MM-dd").format(-86400.0) == "1969-12-31"
    assert DateFormat("MMMM d, yy").format(epoch(1999, 7, 4)) == "July 4, 99"
    assert DateFormat("yy").parse("99") == epoch(1999, 1, 1)


def test_encodings_bom_latin1_utf16_bytes_and_crlf() -> None:
    text = "@relation caf\u00e9\r\n@attribute a {\u00e9t\u00e9,hiver}\r\n@data\r\n\u00e9t\u00e9\r\n"
    expected = loads_arff(text.replace("\r\n", "\n"))
    assert expected.schema.relation == "caf\u00e9"
    for data in (
        text.encode("utf-8"),
        b"\xef\xbb\xbf" + text.encode("utf-8"),
        text.encode("latin-1"),
        text.encode("utf-16"),
        "\ufeff" + text,
    ):
        assert loads_arff(data).equals(expected)


def test_fast_path_and_tokenizer_read_the_same_values() -> None:
    header = (
        "@relation r\n@attribute a numeric\n@attribute b {'x y',z}\n@attribute s string\n@data\n"
    )
    simple = header + "1.5,'x y',abc\n?,z,'d e'\n"
    # Double quotes, escapes and comments force every row through the tokenizer.
    tokenized = header + '1.5 , "x y" , "abc" % c\n? z \'d\\ e\'\n'
    assert loads_arff(simple).equals(loads_arff(tokenized))


# -------------------------------------------------------------------------------- errors


def _error(text: str | bytes) -> DataFormatError:
    with pytest.raises(DataFormatError) as caught:
        loads_arff(text, source="bad.arff")
    error = caught.value
    assert error.source == "bad.arff"
    assert "\n" not in str(error)
    return error


@pytest.mark.parametrize(
    ("text", "message", "line", "attribute"),
    [
        ("", "empty file", None, None),
        ("  \n\t\n", "empty file", None, None),
        (b"\x00\x01\x02binary\x00", "not a text file", None, None),
        (bytes(range(1, 32)) * 20 + b"\xff\xfe", "not a text file", None, None),
        ("% just a comment\n", "no @relation", None, None),
        ("@attribute a numeric\n@data\n", "no @relation", 1, None),
        ("@relation r\n@attribute a numeric\n", "no @data", None, None),
        ("@relation r\n\n@data\n1\n", "no attributes", 3, None),
        (HEADER + "1,x\n2\n", "expected 2 values, found 1", 6, None),
        (HEADER + "1,x\n2,y,3\n", "expected 2 values, found 3", 6, None),
        (HEADER + "1,z\n", "'z' is not one of the declared values {x, y}", 5, "b"),
        (HEADER + "abc,x\n", "'abc' is not a number", 5, "a"),
        (HEADER + "1,'x\n", "unterminated quote", 5, None),
        (HEADER + '1,"x\\"\n', "unterminated quote", 5, None),
        ("@relation r\n@attribute a numeric\n@attribute a {x}\n@data\n", "duplicate", 3, "a"),
        (
            "@relation 'r: -C 2'\n@attribute a numeric\n@attribute b numeric\n@data\n",
            "-C 2",
            1,
            None,
        ),
        (HEADER + "{2 1}\n", "sparse index 2 is out of range 0..1", 5, None),
        (HEADER + "{1 x, 0 1}\n", "sparse indices must increase", 5, None),
        (HEADER + "{a 1}\n", "sparse index 'a' is not an integer", 5, None),
        (HEADER + "{0 1\n", "no closing '}'", 5, None),
        (HEADER + "1,x,{heavy}\n", "instance weight 'heavy' is not a number", 5, None),
        (HEADER + "1,x,{2},3\n", "instance weight", 5, None),
        (
            "@relation r\n@attribute d date 'yyyy-MM-dd'\n@data\n2020-13-01\n",
            "not a valid date for the format 'yyyy-MM-dd': month must be in 1..12",
            4,
            "d",
        ),
        (
            "@relation r\n@attribute d date\n@data\n2020-01-01\n",
            "does not match the date format 'yyyy-MM-dd'T'HH:mm:ss'",
            4,
            "d",
        ),
        (
            "@relation r\n@attribute d date 'yyyy-MM-dd'\n@data\n2021-02-29\n",
            "'2021-02-29' is not a valid date for the format 'yyyy-MM-dd': day is out of range",
            4,
            "d",
        ),
        (
            "@relation r\n@attribute d date 'EEE yyyy'\n@data\n",
            "letter 'E' is not supported",
            2,
            "d",
        ),
        (
            "@relation r\n@attribute bag relational\n@end bag\n@data\n",
            "relational attributes are not supported",
            2,
            "bag",
        ),
        ("@relation r\n@attribute a float\n@data\n", "unknown attribute type 'float'", 2, "a"),
        ("@relation r\n@attribute a {x,x}\n@data\n", "'x' is declared twice", 2, "a"),
        ("@relation r\n@attribute a {x,y\n@data\n", "no closing '}'", 2, "a"),
        ("@relation r\n@attribute a numeric extra\n@data\n", "unexpected 'extra'", 2, "a"),
        ("@relation my data\n@attribute a numeric\n@data\n", "unexpected 'data'", 1, None),
        ("@relation r\n@relation s\n", "a second @relation", 2, None),
        ("@relation r\nhello\n", "expected @attribute or @data", 2, None),
    ],
)
def test_bad_input_raises_one_clear_error_naming_the_place(
    text: str | bytes, message: str, line: int | None, attribute: str | None
) -> None:
    error = _error(text)
    assert message in error.message
    assert error.line == line
    assert error.attribute == attribute
    if line is not None:
        assert f"bad.arff:{line}:" in str(error)


def test_nominal_error_lists_the_allowed_values_truncated() -> None:
    labels = ",".join(f"v{i}" for i in range(30))
    error = _error(f"@relation r\n@attribute a {{{labels}}}\n@attribute b numeric\n@data\nw,1\n")
    assert "'w' is not one of the declared values {v0, v1," in error.message
    assert "v9, ... (30 in all)}" in error.message
    assert "v10" not in error.message


def test_errors_in_fast_path_rows_name_the_right_line() -> None:
    rows = ["1,x"] * 3000
    rows[2500] = "1,nope"
    error = _error(HEADER + "\n".join(rows) + "\n")
    assert error.line == 4 + 2501
    assert error.attribute == "b"


def test_explicit_unknown_target_is_a_data_format_error_naming_the_file() -> None:
    with pytest.raises(DataFormatError, match="no attribute named 'zzz'") as caught:
        loads_arff(HEADER + "1,x\n", source="f.arff", targets=["zzz"])
    assert caught.value.source == "f.arff"


def test_missing_file_and_directory(tmp_path: Path) -> None:
    with pytest.raises(DataFormatError, match="no such file") as caught:
        read_arff(tmp_path / "absent.arff")
    assert caught.value.source == str(tmp_path / "absent.arff")
    with pytest.raises(DataFormatError, match="is a directory"):
        read_arff(tmp_path)


# -------------------------------------------------------------------------------- writing


def test_canonical_file_is_written_back_exactly() -> None:
    assert dumps_arff(loads_arff(CANONICAL)) == CANONICAL


def test_any_spelling_of_a_file_is_written_in_the_canonical_form() -> None:
    messy = loads_arff(MESSY)
    assert messy.schema.attributes[4].declared_type == "STRING"
    assert dumps_arff(messy) == CANONICAL.replace(" string\n", " STRING\n").replace(
        " numeric\n", " NUMERIC\n"
    )


def test_numbers_use_the_shortest_round_trip_text() -> None:
    values = [3.0, -0.0, 0.1, 1 / 3, 1e16, 2.5e-8, -7.0, NAN, math.inf, -math.inf]
    schema = Schema(
        "n",
        (Attribute("a", "numeric", (), "numeric"), Attribute("b", "nominal", ("u",), "nominal")),
        (1,),
    )
    dataset = Dataset(schema, np.column_stack([values, np.zeros(len(values))]))
    text = dumps_arff(dataset)
    rows = text.split("@data\n")[1].splitlines()
    assert [row.split(",")[0] for row in rows] == [
        "3",
        "-0",
        "0.1",
        repr(1 / 3),
        "1e+16",
        "2.5e-08",
        "-7",
        "?",
        "Infinity",
        "-Infinity",
    ]
    back = loads_arff(text)
    assert back.equals(dataset)
    assert math.copysign(1, back.values[1, 0]) == -1


def test_sparse_dataset_is_written_sparse_without_zeros() -> None:
    text = """@relation s
@attribute a numeric
@attribute b {no,yes}
@attribute t string
@attribute d numeric
@data
{1 yes,3 2.5}
{0 ?}
{0 1.5, 2 word}, {3}
"""
    dataset = loads_arff(text)
    written = dumps_arff(dataset)
    assert written.split("@data\n")[1] == (
        "{1 yes,2 word,3 2.5}\n{0 ?,2 word}\n{0 1.5,2 word},{3}\n"
    )
    assert loads_arff(written).equals(dataset)


def test_write_to_path_and_stream(tmp_path: Path) -> None:
    dataset = loads_arff(HEADER + "1,x\n?,y,{2}\n")
    write_arff(dataset, tmp_path / "out.arff")
    stream = io.StringIO()
    write_arff(dataset, stream)
    assert (tmp_path / "out.arff").read_text(encoding="utf-8") == stream.getvalue()
    assert read_arff(tmp_path / "out.arff").equals(dataset)


@pytest.mark.parametrize(
    ("relation", "targets", "written"),
    [
        ("plain", (3,), "plain"),
        ("plain", (0, 1), "'plain: -C 2'"),
        ("plain", (2, 3), "'plain: -C -2'"),
        ("m: -C 2 -split 50", (0, 1, 2), "'m: -C 3 -split 50'"),
        ("m: -C 2", (0, 1), "'m: -C 2'"),
        ("m: -C 2", (3,), "'m: -C -1'"),
        ("m: -split 5", (0,), "'m: -split 5 -C 1'"),
    ],
)
def test_relation_makes_changed_targets_explicit(
    relation: str, targets: tuple[int, ...], written: str
) -> None:
    attributes = tuple(Attribute(n, "numeric", (), "numeric") for n in "abcd")
    dataset = Dataset(Schema(relation, attributes, targets), np.zeros((1, 4)))
    text = dumps_arff(dataset)
    assert text.startswith(f"@relation {written}\n")
    assert loads_arff(text).schema.target_indices == targets


def test_targets_arff_cannot_express_keep_the_stored_relation() -> None:
    attributes = tuple(Attribute(n, "numeric", (), "numeric") for n in "abcd")
    dataset = Dataset(Schema("m: -C 1", attributes, (1, 2)), np.zeros((1, 4)))
    assert dumps_arff(dataset).startswith("@relation 'm: -C 1'\n")


@pytest.mark.parametrize("seconds", [math.inf, 1e15])
def test_writing_an_impossible_date_is_an_error(seconds: float) -> None:
    schema = Schema(
        "r",
        (Attribute("when", "date", (), "date"), Attribute("b", "nominal", ("x",), "nominal")),
        (1,),
    )
    with pytest.raises(DataFormatError, match="cannot write") as caught:
        dumps_arff(Dataset(schema, np.array([[0.0, 0], [seconds, 0]])))
    assert caught.value.attribute == "when"


def test_writing_an_invalid_nominal_code_is_an_error() -> None:
    schema = Schema(
        "r",
        (Attribute("a", "numeric", (), "numeric"), Attribute("b", "nominal", ("x",), "nominal")),
        (1,),
    )
    with pytest.raises(
        DataFormatError, match="row 1 holds 3, which is not the code of any of its 1 nominal values"
    ) as caught:
        dumps_arff(Dataset(schema, np.array([[1, 0], [2, 3]])))
    assert caught.value.attribute == "b"


@pytest.mark.parametrize("seed", range(60))
def test_random_datasets_survive_a_round_trip(seed: int) -> None:
    dataset = random_dataset(np.random.default_rng(seed))
    text = dumps_arff(dataset)
    back = loads_arff(text)
    assert back.equals(dataset), text
    assert back.sparse == (dataset.sparse and dataset.n_instances > 0)
    assert dumps_arff(back) == text


# ----------------------------------------------------------------------------- real data

UC3M = "uc3m-touch"
GESTURES = ("tap", "slap", "stroke", "tickle")


@pytest.mark.parametrize(
    ("robot", "instances", "places"),
    [
        ("mini", 2777, ("head", "left_arm", "right_arm")),
        ("maggie", 3572, ("head", "body_left", "body_right")),
    ],
)
def test_gesture_and_place_files(
    shared_datasets: Path, robot: str, instances: int, places: tuple[str, ...]
) -> None:
    dataset = read_arff(shared_datasets / UC3M / robot / "gesture_and_place.arff")
    assert dataset.schema.relation == "Sound_Gestures: -C 2"
    assert dataset.values.shape == (instances, 101)
    assert dataset.n_features == 99
    assert dataset.schema.target_names == ("gesture", "place")
    gesture, place = dataset.schema.targets
    assert gesture.values == GESTURES
    assert place.values == places
    assert set(np.unique(dataset.Y[:, 0])) == {0, 1, 2, 3}
    assert not np.isnan(dataset.values).any()
    assert all(a.kind == "numeric" for a in dataset.schema.features)
    assert loads_arff(dumps_arff(dataset)).equals(dataset)


@pytest.mark.parametrize("robot", ["mini", "maggie"])
def test_gesture_and_place_values_equal_liac_arff(shared_datasets: Path, robot: str) -> None:
    arff = pytest.importorskip("arff", reason="liac-arff is the oracle of this test")
    path = shared_datasets / UC3M / robot / "gesture_and_place.arff"
    ours = read_arff(path)
    with open(path, encoding="utf-8") as stream:
        theirs = arff.load(stream)
    assert [name for name, _ in theirs["attributes"]] == [a.name for a in ours.schema.attributes]
    assert list(ours.schema.attributes[1].values) == theirs["attributes"][1][1]
    labels = [
        dict(zip(kinds, range(len(kinds)), strict=True)) if isinstance(kinds, list) else None
        for _, kinds in theirs["attributes"]
    ]
    expected = np.array(
        [
            [
                value if lookup is None else lookup[value]
                for value, lookup in zip(row, labels, strict=True)
            ]
            for row in theirs["data"]
        ],
        dtype=float,
    )
    np.testing.assert_array_equal(ours.values, expected)


@pytest.mark.parametrize(
    ("robot", "task", "rows", "n_attributes"),
    [("maggie", "gesture", 140, 71), ("maggie", "place", 140, 71), ("mini", "gesture", 200, 76)],
)
def test_weka_results_files(
    shared_datasets: Path, robot: str, task: str, rows: int, n_attributes: int
) -> None:
    dataset = read_arff(shared_datasets / UC3M / robot / f"weka_results_{task}.arff")
    assert dataset.schema.relation == "InstanceResultListener"
    assert dataset.values.shape == (rows, n_attributes)
    options = dataset.schema.attributes[dataset.schema.index("Key_Scheme_options")]
    assert (
        '-K 1 -W 0 -A "weka.core.neighboursearch.LinearNNSearch -A '
        '\\"weka.core.EuclideanDistance -R first-last\\""'
    ) in options.values
    assert loads_arff(dumps_arff(dataset)).equals(dataset)


def test_weka_results_summary_strings_keep_their_line_breaks(shared_datasets: Path) -> None:
    dataset = read_arff(shared_datasets / UC3M / "maggie" / "weka_results_gesture.arff")
    summary = dataset.schema.attributes[dataset.schema.index("Summary")]
    assert any("\n" in text and "\\n" not in text for text in summary.values)


def test_damaged_results_file_is_rejected_at_its_broken_row(shared_datasets: Path) -> None:
    # Line 207 of this file is the tail of a row whose beginning is lost, and the rows
    # after it come from other experiments whose schemes the header does not declare.
    path = shared_datasets / UC3M / "mini" / "weka_results_place.arff"
    with pytest.raises(DataFormatError, match="unterminated quote") as caught:
        read_arff(path)
    assert caught.value.line == 207
