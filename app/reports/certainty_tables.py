"""How sure, as tables of text cells: each classifier's per-class scores with its
confusion matrix per target, and the calibration of every classifier.  One builder for the
CLI's ``classes`` and ``calibration``, the HTML report and the web page."""

from __future__ import annotations

from app.reports.run_tables import RunTable
from app.schemas.certainty import RunCertainty


def class_tables(certainty: RunCertainty) -> list[RunTable]:
    """Per classifier and target: class, precision, recall, F1, support, then the
    confusion matrix's row of the class (counts predicted as each class)."""
    tables = []
    for entry in certainty.classifiers:
        for target in entry.targets:
            tables.append(
                RunTable(
                    key="classes",
                    title=f"{entry.classifier} on {target.target}: per class, summed over "
                    f"{entry.n_folds} folds (rows true, last columns predicted)",
                    header=("class", "precision", "recall", "F1", "support", *target.labels),
                    rows=[
                        (
                            scores.label,
                            score(scores.precision),
                            score(scores.recall),
                            score(scores.f1),
                            str(scores.support),
                            *(str(count) for count in row),
                        )
                        for scores, row in zip(target.classes, target.confusion, strict=True)
                    ],
                    numeric=(False, *([True] * (4 + len(target.labels)))),
                )
            )
    return tables


def calibration_table(certainty: RunCertainty) -> RunTable:
    """Every classifier's expected calibration error, or why it has none."""
    return RunTable(
        key="calibration",
        title=f"run {certainty.run_id}: calibration of the top label, out of fold "
        "(expected calibration error, 10 bins)",
        header=("classifier", "ECE", "instances", "folds", "note"),
        rows=[
            (
                e.classifier,
                score(e.calibration.ece) if e.calibration else "-",
                str(e.calibration.n_instances) if e.calibration else "-",
                str(e.calibration.n_folds) if e.calibration else "-",
                e.calibration_note or "",
            )
            for e in certainty.classifiers
        ],
        numeric=(False, True, True, True, False),
    )


def score(value: float | None) -> str:
    """Four decimals, ``-`` without a value."""
    return "-" if value is None else f"{value:.4f}"
