"""A grasp table as other labs publish them, written for the tests: one row per grasp, the
object grasped in a column, a trial number, tactile features and a ``slipped`` label."""

from __future__ import annotations

from pathlib import Path

import numpy as np

OBJECTS = ("mug", "ball", "box", "can", "cup", "pen", "egg", "toy")
FEATURES = tuple(f"taxel{i}" for i in range(6))
#: The file's columns, in order.
COLUMNS = ("object", "trial", *FEATURES, "slipped")


def grasp_rows(
    *, objects: int = 8, grasps: int = 10, seed: int = 0
) -> list[tuple[str, int, list[float], str]]:
    """``objects * grasps`` rows: object, trial, six features, and ``yes``/``no`` slipped.

    Both labels occur for every object, and the first feature tells them apart.
    """
    rng = np.random.default_rng(seed)
    rows = []
    for name in OBJECTS[:objects]:
        for trial in range(grasps):
            slipped = trial % 2 == 1
            values = rng.normal(size=len(FEATURES))
            values[0] += 2.5 if slipped else 0.0
            rows.append((name, trial + 1, [float(v) for v in values], "yes" if slipped else "no"))
    return rows


def grasp_csv(
    path: Path,
    *,
    objects: int = 8,
    grasps: int = 10,
    seed: int = 0,
    missing_group_at: int | None = None,
) -> Path:
    """The table as CSV; ``missing_group_at``: that 0-based row's object cell left empty."""
    lines = [",".join(COLUMNS)]
    for i, (name, trial, values, slipped) in enumerate(
        grasp_rows(objects=objects, grasps=grasps, seed=seed)
    ):
        shown = "" if i == missing_group_at else name
        lines.append(",".join([shown, str(trial), *(f"{v:.5f}" for v in values), slipped]))
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def grasp_arff(
    path: Path, *, objects: int = 8, grasps: int = 10, seed: int = 0, kind: str = "nominal"
) -> Path:
    """The table as ARFF; the object column is ``kind``: nominal, string or numeric (then
    the object's number, 1 for the first)."""
    names = OBJECTS[:objects]
    declared = {"nominal": "{" + ",".join(names) + "}", "string": "string", "numeric": "numeric"}
    lines = ["@relation grasps", f"@attribute object {declared[kind]}", "@attribute trial numeric"]
    lines += [f"@attribute {name} numeric" for name in FEATURES]
    lines += ["@attribute slipped {no,yes}", "@data"]
    for name, trial, values, slipped in grasp_rows(objects=objects, grasps=grasps, seed=seed):
        shown = str(names.index(name) + 1) if kind == "numeric" else name
        lines.append(",".join([shown, str(trial), *(f"{v:.5f}" for v in values), slipped]))
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path
