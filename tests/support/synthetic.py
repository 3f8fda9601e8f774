"""Small ARFF files with a learnable structure, written for the app tests."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from touchbench.benchmark.dataset import Attribute, Dataset, Schema


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


def small_dataset(n: int = 7, relation: str = "touch: -C 1") -> Dataset:
    schema = Schema(
        relation=relation,
        attributes=(
            Attribute("gesture", "nominal", ("tap", "slap", "stroke")),
            Attribute("energy", "numeric", declared_type="real"),
            Attribute("count", "numeric", declared_type="integer"),
            Attribute("note", "string", ("first", "second")),
            Attribute("when", "date"),
        ),
        target_indices=(0,),
    )
    rng = np.random.default_rng(0)
    values = np.column_stack(
        [
            np.arange(n) % 3,
            rng.normal(size=n),
            np.arange(n) * 10,
            np.arange(n) % 2,
            1.7e9 + np.arange(n) * 60,
        ]
    ).astype(float)
    values[2, 1] = np.nan
    values[4, 0] = np.nan
    return Dataset(schema=schema, values=values)


def mics_arff(path: Path, *, n: int = 90, seed: int = 0) -> Path:
    """Microphone 1 hears the gesture (level_1), microphone 2 only noise."""
    rng = np.random.default_rng(seed)
    y = np.arange(n) % 3
    lines = ["@relation mics"]
    lines += [f"@attribute {name} numeric" for name in ("level_1", "snr_1", "level_2", "snr_2")]
    lines += ["@attribute gesture {tap,slap,stroke}", "@data"]
    for label in y:
        level, *noise = label + rng.normal(scale=0.2), *rng.normal(size=3)
        values = ",".join(f"{v:.4f}" for v in (level, noise[0], noise[1], noise[2]))
        lines.append(f"{values},{('tap', 'slap', 'stroke')[label]}")
    path.write_text("\n".join(lines) + "\n")
    return path


TOUCH_ARFF = """% two targets, MEKA style
@relation 'touch: -C 2'
@attribute gesture {tap, slap, 'soft stroke'}
@attribute place {head, arm}
@attribute energy numeric
@attribute zcr integer
@attribute mic {left, right}
@data
tap, head, 0.5, 3, left
slap, arm, 1.25, 7, right
'soft stroke', head, ?, 2, left
tap, arm, 0.75, ?, ?
"""


def write(tmp_path: Path, name: str, text: str | bytes) -> Path:
    path = tmp_path / name
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text, encoding="utf-8")
    return path


def nominal_dataset(n: int = 90, targets: int = 1) -> Dataset:
    rng = np.random.default_rng(0)
    gesture = np.arange(n) % 3
    place = (np.arange(n) // 3) % 2
    colour = (gesture + (rng.random(n) < 0.2)) % 2
    level = 0.3 * rng.normal(size=n) + 6.0 * gesture + 2.0 * place
    attributes = [
        Attribute("gesture", "nominal", ("tap", "slap", "stroke")),
        Attribute("place", "nominal", ("head", "arm")),
        Attribute("colour", "nominal", ("red", "blue")),
        Attribute("note", "string", ("a", "b")),
        Attribute("level", "numeric", (), "numeric"),
    ]
    values = np.column_stack([gesture, place, colour, np.zeros(n), level]).astype(np.float64)
    values[::10, 4] = np.nan
    target_indices = (0,) if targets == 1 else (0, 1)
    return Dataset(Schema("touch", tuple(attributes), target_indices), values)
