"""Small ARFF files with a learnable structure, written for the app tests."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def touch_arff(
    path: Path,
    *,
    n: int = 90,
    seed: int = 0,
    with_place: bool = True,
    one_class: bool = False,
) -> Path:
    """Gesture (3 classes) [and place (2)] from 4 numeric features, a nominal one and gaps.

    The features separate the classes well, so any sensible classifier beats ZeroR.
    """
    rng = np.random.default_rng(seed)
    gestures = ["tap", "slap", "stroke"]
    places = ["head", "arm"]
    lines = [f"@relation 'touch: -C {2 if with_place else 1}'"]
    lines.append("@attribute gesture {tap, slap, stroke}")
    if with_place:
        lines.append("@attribute place {head, arm}")
    lines += [f"@attribute f{i} numeric" for i in range(4)]
    lines += ["@attribute mic {left, right, both}", "@data"]
    for i in range(n):
        g = 0 if one_class else i % 3
        p = (i // 3) % 2
        x = rng.normal(size=4) * 0.6
        x[0] += 2.0 * g
        x[1] += 2.0 * p
        cells = [f"{v:.4f}" if rng.random() > 0.03 else "?" for v in x]
        row = [gestures[g]] + ([places[p]] if with_place else []) + cells
        row.append(["left", "right", "both"][(g + p) % 3])
        lines.append(",".join(row))
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def position_arff(path: Path, *, n: int = 60, seed: int = 0) -> Path:
    """Contact position (x, y in cm, the last two attributes) from 3 numeric features and a
    nominal one: MEKA's ``-C -2`` header; x is linear in the features, y smooth."""
    rng = np.random.default_rng(seed)
    lines = ["@relation 'contact: -C -2'"]
    lines += [f"@attribute f{i} numeric" for i in range(3)]
    lines += ["@attribute mic {left, right}", "@attribute x numeric", "@attribute y numeric"]
    lines.append("@data")
    for i in range(n):
        f = rng.normal(size=3)
        x = 10.0 * f[0] - 4.0 * f[1] + rng.normal() * 0.2
        y = 5.0 * np.tanh(f[2]) + 2.0 * (i % 2) + rng.normal() * 0.2
        cells = [f"{v:.4f}" for v in f] + [["left", "right"][i % 2], f"{x:.3f}", f"{y:.3f}"]
        lines.append(",".join(cells))
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path
