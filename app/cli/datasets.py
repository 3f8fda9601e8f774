"""Commands for data sets: import, datasets, show, export, delete."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer

from app.cli.output import info, print_json, table
from app.cli.state import get_state
from app.services.datasets import import_file, parse_targets
from app.store.datasets import (
    DatasetInfo,
    delete_dataset,
    find_dataset,
    list_datasets,
    load_dataset,
)
from benchmark.dataset import Dataset
from benchmark.io.arff import write_arff

JsonOption = Annotated[bool, typer.Option("--json", help="Print only JSON on stdout.")]
DatasetArgument = Annotated[str, typer.Argument(metavar="DATASET", help="Data set name or id.")]


def register(app: typer.Typer) -> None:
    app.command("import")(import_command)
    app.command("datasets")(datasets_command)
    app.command("show")(show_command)
    app.command("export")(export_command)
    app.command("delete")(delete_command)


def import_command(
    ctx: typer.Context,
    file: Annotated[Path, typer.Argument(help="ARFF or CSV file.", show_default=False)],
    name: Annotated[
        str | None, typer.Option("--name", help="Name in the store (default: the relation).")
    ] = None,
    targets: Annotated[
        str | None,
        typer.Option(
            "--targets",
            metavar="N|NAMES",
            help=(
                "Targets: N first attributes, -N last ones, or comma-separated names. "
                "Default: MEKA's '-C N' in the relation, else the last attribute (WEKA)."
            ),
        ),
    ] = None,
    file_format: Annotated[
        str | None,
        typer.Option(
            "--format", metavar="arff|csv", help="File format (default: by the file's ending)."
        ),
    ] = None,
    as_json: JsonOption = False,
) -> None:
    """Import an ARFF or CSV file as a data set (nothing is stored if the file has an error)."""
    if file_format is not None and file_format not in ("arff", "csv"):
        raise typer.BadParameter(f"'{file_format}' is not arff or csv", param_hint="--format")
    store = get_state(ctx).store
    dataset_info, created = import_file(
        store,
        file,
        name=name,
        targets=parse_targets(targets),
        file_format=file_format,  # type: ignore[arg-type]
    )
    if as_json:
        print_json({**_summary(dataset_info), "created": created})
        return
    if not created:
        info(
            f"{file} is already stored as dataset {dataset_info.id} '{dataset_info.name}'; "
            "nothing imported"
        )
    _print_summary(dataset_info)


def datasets_command(ctx: typer.Context, as_json: JsonOption = False) -> None:
    """List the data sets in the store."""
    rows = list_datasets(get_state(ctx).store)
    if as_json:
        print_json({"datasets": [row.to_json() for row in rows]})
        return
    if not rows:
        info("no datasets yet: `touchbench import FILE` adds one")
        return
    table(
        None,
        ["id", "name", "instances", "features", "targets", "source", "imported"],
        [
            (
                row.id,
                row.name,
                row.n_instances,
                row.n_features,
                ", ".join(row.targets),
                row.source_name,
                row.created_at.strftime("%Y-%m-%d %H:%M"),
            )
            for row in rows
        ],
        justify=["right", "left", "right", "right", "left", "left", "left"],
    )


def show_command(ctx: typer.Context, dataset: DatasetArgument, as_json: JsonOption = False) -> None:
    """Show a data set's schema, class distribution per target and missing values."""
    store = get_state(ctx).store
    dataset_info = find_dataset(store, dataset)
    data = load_dataset(store, dataset_info.id)
    description = describe(dataset_info, data)
    if as_json:
        print_json(description)
        return
    _print_summary(dataset_info)
    table(
        "attributes",
        ["#", "name", "role", "type", "labels / range", "missing"],
        [
            (
                i + 1,
                a["name"],
                a["role"],
                a["kind"],
                _labels_or_range(a),
                a["missing"],
            )
            for i, a in enumerate(description["attributes"])
        ],
        justify=["right", "left", "left", "left", "left", "right"],
    )
    for target, counts in description["class_distribution"].items():
        total = sum(counts.values()) or 1
        table(
            f"class distribution of {target}",
            ["label", "instances", "share"],
            [(label, n, f"{100 * n / total:.1f} %") for label, n in counts.items()],
            justify=["left", "right", "right"],
        )
    info(f"missing values: {description['missing_values']}")


def export_command(
    ctx: typer.Context,
    dataset: DatasetArgument,
    output: Annotated[
        Path | None, typer.Option("-o", "--output", help="File to write (default: stdout).")
    ] = None,
) -> None:
    """Write a data set back as ARFF (the relation keeps MEKA's -C header for its targets)."""
    store = get_state(ctx).store
    data = load_dataset(store, find_dataset(store, dataset).id)
    if output is None:
        write_arff(data, sys.stdout)
        return
    write_arff(data, output)
    info(f"wrote {data.n_instances} instances to {output}")


def delete_command(ctx: typer.Context, dataset: DatasetArgument) -> None:
    """Delete a data set with its instances, runs and results."""
    gone = delete_dataset(get_state(ctx).store, dataset)
    info(f"deleted dataset {gone.id} '{gone.name}' ({gone.n_instances} instances)")


def describe(dataset_info: DatasetInfo, data: Dataset) -> dict[str, Any]:
    """Schema, per-attribute missing counts and ranges, class distribution per target."""
    schema = data.schema
    targets = set(schema.target_indices)
    missing = np.isnan(data.values).sum(axis=0)
    attributes = []
    for i, attribute in enumerate(schema.attributes):
        column = data.values[:, i]
        entry: dict[str, Any] = {
            "name": attribute.name,
            "kind": attribute.kind,
            "role": "target" if i in targets else "feature",
            "missing": int(missing[i]),
        }
        if attribute.kind == "nominal":
            entry["values"] = list(attribute.values)
        elif attribute.kind == "numeric" and np.isfinite(column).any():
            entry["min"] = float(np.nanmin(column))
            entry["max"] = float(np.nanmax(column))
        attributes.append(entry)
    distribution: dict[str, dict[str, int]] = {}
    for i in schema.target_indices:
        attribute = schema.attributes[i]
        if attribute.kind != "nominal":
            continue
        codes = data.values[:, i]
        counts = np.bincount(codes[~np.isnan(codes)].astype(int), minlength=len(attribute.values))
        distribution[attribute.name] = {
            label: int(n) for label, n in zip(attribute.values, counts, strict=True)
        }
    return {
        **_summary(dataset_info),
        "relation": schema.relation,
        "attributes": attributes,
        "class_distribution": distribution,
        "missing_values": int(missing.sum()),
    }


def _summary(dataset_info: DatasetInfo) -> dict[str, Any]:
    return {
        "id": dataset_info.id,
        "name": dataset_info.name,
        "n_instances": dataset_info.n_instances,
        "n_features": dataset_info.n_features,
        "targets": dataset_info.targets,
    }


def _print_summary(dataset_info: DatasetInfo) -> None:
    table(
        None,
        ["id", "name", "instances", "features", "targets"],
        [
            (
                dataset_info.id,
                dataset_info.name,
                dataset_info.n_instances,
                dataset_info.n_features,
                ", ".join(dataset_info.targets),
            )
        ],
        justify=["right", "left", "right", "right", "left"],
    )


def _labels_or_range(attribute: dict[str, Any]) -> str:
    if "values" in attribute:
        labels = attribute["values"]
        shown = ", ".join(labels[:6])
        return shown + (f", ... ({len(labels)})" if len(labels) > 6 else "")
    if "min" in attribute:
        return f"{attribute['min']:.4g} .. {attribute['max']:.4g}"
    return ""
