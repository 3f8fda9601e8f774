"""ARFF texts the reader and writer tests share: WEKA's header, a canonical and a messy
file, tricky strings, and random data sets of every attribute kind."""

from __future__ import annotations

import math

import numpy as np

from touchbench.benchmark.dataset import Attribute, Dataset, Schema, resolve_targets

HEADER = "@relation r\n@attribute a numeric\n@attribute b {x,y}\n@data\n"


CANONICAL = r"""@relation 'canonical: -C 2'

@attribute 'a b' {x,'y z','it\'s',''}
@attribute c {0,1}
@attribute n numeric
@attribute r REAL
@attribute s string
@attribute d date 'yyyy-MM-dd HH:mm'

@data
x,0,3,-0.5,hello,'2020-01-02 03:04'
'y z',1,1e-300,1.5e+20,'a,b','1969-07-20 20:17'
'it\'s',?,?,?,?,?,{0.5}
'',1,123456789,Infinity,'line\nbreak\ttab\\ \"q\" 100\% \001',?
"""


MESSY = r"""% the same data as CANONICAL, written differently
@RELATION "canonical: -C 2"
@ATTRIBUTE "a b" { x , "y z" , "it's" , "" }
@attribute 'c' {'0', '1'}
@attribute n NUMERIC
@attribute r REAL
@attribute s STRING
@attribute d date "yyyy-MM-dd HH:mm"
@data
'x', '0', 3.0, -.5, "hello", "2020-01-02 03:04"  % a comment
"y z" 1 1.0e-300 15e19 "a,b" '1969-07-20 20:17'
"it's",?,?,?,?,?,{0.50}
"", "1", 123456789.000, Infinity, "line\nbreak\ttab\\ \"q\" 100% \1", ?
"""


TRICKY = [
    "a",
    "Z",
    "0",
    "-",
    ".",
    " ",
    ",",
    "'",
    '"',
    "\\",
    "%",
    "{",
    "}",
    "?",
    "@",
    "\n",
    "\r",
    "\t",
    "\x00",
    "\x01",
    "\x0b",
    "\x7f",
    "\x85",
    "\xa0",
    "\u00e9",
    "\u20ac",
    "\u2028",
    "\U0001f600",
]


def random_dataset(rng: np.random.Generator) -> Dataset:
    n_rows = int(rng.integers(0, 6))
    attributes: list[Attribute] = []
    columns: list[np.ndarray] = []
    names: set[str] = set()
    for _ in range(int(rng.integers(2, 7))):
        name = tricky_text(rng)
        while name in names:
            name += "x"
        names.add(name)
        kind = KINDS[int(rng.integers(len(KINDS)))]
        if kind == "numeric":
            pool = [0.0, -0.0, 1.0, -2.5, 1e300, 5e-324, NAN, math.inf, 1 / 7, 12345678901.0]
            column = np.array(rng.choice(pool, size=n_rows))
            declared = "numeric" if rng.random() < 0.5 else "REAL"
            attributes.append(Attribute(name, "numeric", (), declared))
        elif kind == "date":
            pattern = DATE_PATTERNS[int(rng.integers(len(DATE_PATTERNS)))]
            column = rng.integers(-2_000_000_000, 4_000_000_000, size=n_rows).astype(float)
            if pattern is not None:  # only patterns with S keep milliseconds
                column += rng.integers(0, 1000, size=n_rows) / 1000
            column[rng.random(n_rows) < 0.2] = NAN
            attributes.append(Attribute(name, "date", (), "date", pattern))
        else:
            labels = list(dict.fromkeys(tricky_text(rng) for _ in range(int(rng.integers(1, 5)))))
            column = rng.integers(0, len(labels), size=n_rows).astype(float)
            column[rng.random(n_rows) < 0.2] = NAN
            if kind == "string":  # a string table lists values as they first appear
                order = list(dict.fromkeys(int(c) for c in column if not np.isnan(c)))
                labels = [labels[c] for c in order]
                column = np.array([NAN if np.isnan(c) else order.index(int(c)) for c in column])
                attributes.append(Attribute(name, "string", tuple(labels), "string"))
            else:
                attributes.append(Attribute(name, "nominal", tuple(labels), "nominal"))
        columns.append(column)
    relation = tricky_text(rng)
    targets = resolve_targets(None, [a.name for a in attributes], relation=relation)
    weights = None
    if rng.random() < 0.5:
        weights = rng.choice([1.0, 0.5, 2.0, 0.0], size=n_rows)
    values = np.column_stack(columns) if n_rows else np.empty((0, len(attributes)))
    return Dataset(
        Schema(relation, tuple(attributes), targets),
        values,
        weights=weights,
        sparse=bool(rng.random() < 0.5),
    )


NAN = np.nan


def tricky_text(rng: np.random.Generator) -> str:
    return "".join(rng.choice(TRICKY, size=int(rng.integers(0, 6))))


KINDS = ("numeric", "nominal", "string", "date")


DATE_PATTERNS = (None, "yyyy-MM-dd HH:mm:ss.SSS", "d/M/yyyy'T'H:m:s.SSSZ")
