"""WEKA ARFF files: read them into, and write them from, :class:`~benchmark.dataset.Dataset`.

Everything WEKA's ``ArffLoader`` reads is read: dense and sparse rows, instance weights,
numeric, nominal, string and date attributes, missing values, quotes with escapes,
comments, and MEKA's ``-C`` target option in the relation name.  Relational attributes
are not supported.  ``loads_arff(dumps_arff(d))`` equals ``d``.  Large files stream:
:func:`open_arff` reads blocks of instances, :class:`ArffWriter` writes them.
"""

from __future__ import annotations

from touchbench.benchmark.io.arff_reader import ArffReader, loads_arff, open_arff, read_arff
from touchbench.benchmark.io.arff_writer import ArffWriter, dumps_arff, write_arff

__all__ = [
    "ArffReader",
    "ArffWriter",
    "dumps_arff",
    "loads_arff",
    "open_arff",
    "read_arff",
    "write_arff",
]
