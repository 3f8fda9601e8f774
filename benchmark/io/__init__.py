"""Data files in and out: WEKA/MEKA ARFF and CSV read into, and written from,
:class:`~benchmark.dataset.Dataset`, with errors that name the file, line and attribute.

This sub-package owns file formats only; it never imports scikit-learn (an import-linter
contract keeps it so), so reading a file costs no machine-learning start-up.
"""

from __future__ import annotations

from touchbench.benchmark.io.arff import dumps_arff, loads_arff, read_arff, write_arff
from touchbench.benchmark.io.columns import ColumnChoice, ColumnError
from touchbench.benchmark.io.csv import read_csv

__all__ = [
    "ColumnChoice",
    "ColumnError",
    "dumps_arff",
    "loads_arff",
    "read_arff",
    "read_csv",
    "write_arff",
]
