"""How sure, as tables of text cells: each classifier's per-class scores with its
confusion matrix per target, and the calibration of every classifier.  One builder for the
CLI's ``classes`` and ``calibration``, the HTML report and the web page."""

from __future__ import annotations

from touchbench.app.reports.run_tables import RunTable
from touchbench.app.schemas.certainty import Calibration, ClassifierCertainty, RunCertainty


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
    """Every classifier's expected calibration error (per target in a multi-target run), or
    why it has none."""
    rows = []
    for e, target, calibration in calibrations(certainty):
        rows.append(
            (
                e.classifier,
                *((target or "-",) if certainty.kind == "multitarget" else ()),
                score(calibration.ece) if calibration else "-",
                str(calibration.n_instances) if calibration else "-",
                str(calibration.n_folds) if calibration else "-",
                "" if calibration else e.calibration_note or "",
            )
        )
    per_target = certainty.kind == "multitarget"
    return RunTable(
        key="calibration",
        title=f"run {certainty.run_id}: calibration of the top label, out of fold "
        "(expected calibration error, 10 bins" + (", per target)" if per_target else ")"),
        header=(
            "classifier",
            *(("target",) if per_target else ()),
            "ECE",
            "instances",
            "folds",
            "note",
        ),
        rows=rows,
        numeric=(False, *((False,) if per_target else ()), True, True, True, False),
    )


def calibrations(
    certainty: RunCertainty,
) -> list[tuple[ClassifierCertainty, str | None, Calibration | None]]:
    """(classifier, target, calibration) of each classifier, per target in a multi-target
    run (target ``None`` otherwise)."""
    out: list[tuple[ClassifierCertainty, str | None, Calibration | None]] = []
    for entry in certainty.classifiers:
        if certainty.kind != "multitarget":
            out.append((entry, None, entry.calibration))
            continue
        for target in entry.targets:
            out.append((entry, target.target, target.calibration))
    return out


def score(value: float | None) -> str:
    """Four decimals, ``-`` without a value."""
    return "-" if value is None else f"{value:.4f}"
