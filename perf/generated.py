"""A Maggie-like ARFF file of any size, for the perf scripts (not a test fixture).

Two quoted nominal targets (``'tap','head'``, MEKA's ``-C 2``) and 99 numeric features
with five decimals and one zero in twenty: about 850 bytes a row, so 235 000 rows make the
200 MB file of issue 14.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

GESTURES = ("tap", "slap", "stroke", "tickle")
PLACES = ("head", "body_left", "body_right")
_DISTINCT_ROWS = 5000


def write_maggie_like(path: Path, rows: int, *, seed: int = 0) -> Path:
    """Write ``rows`` instances (5000 distinct ones, repeated) to ``path``."""
    rng = np.random.default_rng(seed)
    header = ["@relation 'Sound_Gestures: -C 2'"]
    header.append("@attribute gesture {" + ",".join(f"'{g}'" for g in GESTURES) + "}")
    header.append("@attribute place {" + ",".join(f"'{p}'" for p in PLACES) + "}")
    header += [f"@attribute feature_{i} numeric" for i in range(99)]
    values = np.round(rng.lognormal(3, 2, size=(_DISTINCT_ROWS, 99)), 5)
    values[rng.random(values.shape) < 0.05] = 0
    lines = []
    for i, row in enumerate(values.tolist()):
        numbers = ",".join(repr(v).removesuffix(".0") for v in row)
        lines.append(f"'{GESTURES[i % 4]}','{PLACES[i % 3]}',{numbers}\n")
    block = "".join(lines).encode()
    with open(path, "wb") as stream:
        stream.write(("\n".join(header) + "\n@data\n").encode())
        for _ in range(rows // _DISTINCT_ROWS):
            stream.write(block)
        stream.write("".join(lines[: rows % _DISTINCT_ROWS]).encode())
    return path
