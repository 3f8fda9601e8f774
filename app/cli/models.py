"""Commands for models: train, models, predict, and the aliases of their versions: alias,
promote, rollback."""

from __future__ import annotations

# Imports inside functions: start-up time. This module holds several commands and the
# one chosen loads only what it uses (the CLI imports the module when a command of it
# is chosen).
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from touchbench.app.cli.output import EngineOption, JsonOption, info, print_json, table, warn
from touchbench.app.cli.state import get_state

if TYPE_CHECKING:
    from touchbench.app.schemas.models import AliasRequest
    from touchbench.app.store.aliases import AliasMove


def register(app: typer.Typer) -> None:
    app.command("train")(train_command)
    app.command("models")(models_command)
    app.command("predict")(predict_command)
    app.command("delete-model")(delete_model_command)
    app.command("export-model")(export_model_command)
    app.command("alias")(alias_command)
    app.command("promote")(promote_command)
    app.command("rollback")(rollback_command)


def train_command(
    ctx: typer.Context,
    dataset: Annotated[
        str, typer.Argument(metavar="DATASET", help="Data set name or id.", show_default=False)
    ],
    classifier: Annotated[
        str,
        typer.Option(
            "--classifier",
            "-c",
            metavar="ID",
            help="Classifier id (see `touchbench classifiers`).",
            show_default=False,
        ),
    ],
    target: Annotated[
        str | None,
        typer.Option("--target", metavar="NAME", help="Train for this one target only."),
    ] = None,
    name: Annotated[
        str | None,
        typer.Option(
            "--name",
            metavar="NAME",
            help="Model name (default: DATASET-CLASSIFIER); a name already taken gets its "
            "next version.",
        ),
    ] = None,
    seed: Annotated[
        int | None,
        typer.Option("--seed", metavar="S", help="Seed of the classifier.", show_default="0"),
    ] = None,
    onnx: Annotated[
        bool,
        typer.Option(
            "--onnx",
            help="Also make the model's ONNX twin, checked against it on the training "
            "instances (predictions with --engine auto then run it).",
        ),
    ] = False,
    as_json: JsonOption = False,
) -> None:
    """Fit a classifier on every instance of a data set and store the model."""
    from touchbench.app.cli.requests import build_request
    from touchbench.app.schemas.models import TrainRequest
    from touchbench.app.services.models import train

    request = build_request(
        TrainRequest,
        {"dataset": "DATASET", "classifier": "--classifier"},
        dataset=dataset,
        classifier=classifier,
        target=target,
        name=name,
        seed=seed,
        onnx=onnx,
    )
    model = train(get_state(ctx).store, request)
    if as_json:
        print_json(model.to_json())
        return
    twin = "" if model.twin is None else f"; its ONNX twin {model.twin.size_bytes:,} bytes"
    info(
        f"trained model {model.id} '{model.label}': {model.classifier} on {model.dataset_name} "
        f"for {', '.join(model.targets)} ({model.size_bytes:,} bytes, sha256 "
        f"{model.sha256[:12]}{twin})"
    )


def models_command(ctx: typer.Context, as_json: JsonOption = False) -> None:
    """List trained models, a row per version, with their aliases (artifacts are not read)."""
    from touchbench.app.schemas.models import ModelList
    from touchbench.app.services.registry import list_models

    models = list_models(get_state(ctx).store)
    if as_json:
        print_json(ModelList(models=[m.to_schema() for m in models]).to_json())
        return
    if not models:
        info("no models yet: `touchbench train DATASET --classifier ID` makes one")
        return
    table(
        None,
        [
            "id",
            "name",
            "version",
            "aliases",
            "classifier",
            "dataset",
            "targets",
            "bytes",
            "live",
            "trained",
        ],
        [
            (
                m.id,
                m.name,
                m.version,
                ", ".join(m.aliases),
                m.classifier,
                m.dataset_name,
                ", ".join(m.targets),
                f"{m.size_bytes:,}",
                "✓" if m.extraction else "",
                m.created_at.strftime("%Y-%m-%d %H:%M"),
            )
            for m in models
        ],
    )


def predict_command(
    ctx: typer.Context,
    model_ref: Annotated[
        str,
        typer.Argument(
            metavar="MODEL",
            help="Model id, NAME (its newest version), NAME@VERSION or NAME@ALIAS.",
            show_default=False,
        ),
    ],
    file: Annotated[
        Path,
        typer.Argument(
            metavar="FILE",
            help="ARFF or CSV file with the model's attributes (matched by name).",
            show_default=False,
        ),
    ],
    engine: EngineOption = None,
    as_json: JsonOption = False,
) -> None:
    """Predict every instance of a file; attributes are matched to the model's by name."""
    from touchbench.app.cli.requests import build_request
    from touchbench.app.schemas.models import PredictFileRequest
    from touchbench.app.services.models import predict_file

    request = build_request(
        PredictFileRequest,
        {"model": "MODEL", "file": "FILE"},
        model=model_ref,
        file=file,
        engine=engine,
    )
    report = predict_file(get_state(ctx).store, request)
    if as_json:
        print_json(report.to_json())
        return
    rows = [row.model_dump() for row in report.predictions]
    columns = ["#", *report.targets]
    with_probabilities = bool(rows) and rows[0].get("probabilities") is not None
    if with_probabilities:
        columns += [f"p({t})" for t in report.targets]
    table(
        f"{len(rows)} predictions by {report.model}",
        columns,
        [
            (
                row["instance"],
                *(_cell(row[t]) for t in report.targets),
                *(
                    f"{row['probabilities'][t][row[t]]:.3f}"
                    for t in report.targets
                    if with_probabilities
                ),
            )
            for row in rows
        ],
    )
    for warning in report.warnings:
        warn(warning)
    for target, accuracy in report.accuracy.items():
        info(f"accuracy on {target} (the file carries the true labels): {accuracy:.4f}")
    for target, error in report.mae.items():
        info(f"mean absolute error on {target} (the file carries the true values): {error:.4g}")


def _cell(value: object) -> object:
    """A predicted label as it is, a predicted number to 4 significant digits."""
    return f"{value:.4g}" if isinstance(value, float) else value


def delete_model_command(
    ctx: typer.Context,
    model_ref: Annotated[
        str, typer.Argument(metavar="MODEL", help="Model name or id.", show_default=False)
    ],
) -> None:
    """Delete a trained model (one version: NAME alone is its newest)."""
    from touchbench.app.services.registry import delete_model

    gone = delete_model(get_state(ctx).store, model_ref)
    info(f"deleted model {gone.id} '{gone.label}'")


def export_model_command(
    ctx: typer.Context,
    model_ref: Annotated[
        str, typer.Argument(metavar="MODEL", help="Model name or id.", show_default=False)
    ],
    output: Annotated[
        Path,
        typer.Option(
            "--output", "-o", metavar="FILE", help="The file to write.", show_default=False
        ),
    ],
    format: Annotated[
        str, typer.Option("--format", metavar="FORMAT", help="onnx: one ONNX graph.")
    ] = "onnx",
    force: Annotated[bool, typer.Option("--force", help="Overwrite FILE if it exists.")] = False,
    as_json: JsonOption = False,
) -> None:
    """Write a model as one ONNX graph (preprocessing and classifier), checked against the
    model on its training instances; predictions then run it in ONNX Runtime.

    The graph's input is `features` (float32, one column per attribute in the order the
    metadata key touchbench.features lists them; a nominal attribute as the index of its
    label), its outputs `label` (an index into touchbench.labels) and `probabilities`. It
    is kept in the store: `predict` and `live` run it (--engine).
    """
    from touchbench.app.cli.requests import build_request
    from touchbench.app.errors import FieldError
    from touchbench.app.schemas.models import ExportRequest
    from touchbench.app.services.export import export_model

    request = build_request(
        ExportRequest, {"model": "MODEL", "format": "--format"}, model=model_ref, format=format
    )
    if output.exists() and not force:
        raise FieldError("output", f"{output.name} exists; give --force to overwrite it")
    if not output.parent.is_dir():  # refused before the twin is made and stored
        raise FieldError("output", f"folder {output.parent} does not exist")
    exported, graph = export_model(get_state(ctx).store, request)
    output.write_bytes(graph)
    if as_json:
        print_json({**exported.to_json(), "path": str(output)})
        return
    info(
        f"wrote {output} ({exported.size_bytes:,} bytes, sha256 {exported.sha256[:12]}): model "
        f"'{exported.model}' as ONNX, same labels and probabilities within 1e-5 on its "
        f"{exported.checked_instances} training instances"
    )


_VERSION_ARGUMENT = typer.Argument(
    metavar="MODEL@VERSION",
    help="The version: NAME@VERSION (or an id, NAME for the newest, NAME@ALIAS).",
    show_default=False,
)


def alias_command(
    ctx: typer.Context,
    model_ref: Annotated[str, _VERSION_ARGUMENT],
    alias: Annotated[
        str,
        typer.Argument(metavar="ALIAS", help="The alias, e.g. champion.", show_default=False),
    ],
    delete: Annotated[
        bool,
        typer.Option(
            "--delete",
            help="Delete the alias instead (MODEL: the name, or NAME@VERSION to delete it "
            "only while it points there); sessions following it keep their version.",
        ),
    ] = False,
    as_json: JsonOption = False,
) -> None:
    """Point an alias of a model (NAME@ALIAS) at one of its versions."""
    from touchbench.app.schemas.references import parse_model_ref
    from touchbench.app.services.models import move_alias, remove_alias

    request = _alias_request(model_ref, alias)
    if not delete:
        _moved(move_alias(get_state(ctx).store, request), as_json)
        return
    gone = remove_alias(get_state(ctx).store, request)
    if as_json:
        print_json(gone.to_json())
        return
    name = parse_model_ref(gone.model).name
    info(f"deleted {name}@{gone.alias} (it pointed at version {gone.version})")


def promote_command(
    ctx: typer.Context,
    model_ref: Annotated[str, _VERSION_ARGUMENT],
    as_json: JsonOption = False,
) -> None:
    """Make a version the model's champion: NAME@champion, which `live`, `serve` and live
    WebSocket sessions on it follow, answers with it from now on (`rollback` undoes)."""
    from touchbench.app.services.models import move_alias

    _moved(move_alias(get_state(ctx).store, _alias_request(model_ref, None)), as_json)


def rollback_command(
    ctx: typer.Context,
    model_ref: Annotated[
        str,
        typer.Argument(
            metavar="MODEL", help="Model name (or any of its versions).", show_default=False
        ),
    ],
    alias: Annotated[
        str | None,
        typer.Option(
            "--alias", metavar="ALIAS", help="The alias to step back.", show_default="champion"
        ),
    ] = None,
    as_json: JsonOption = False,
) -> None:
    """Point the champion (or --alias) back at the version it pointed at before its last move."""
    from touchbench.app.services.models import roll_back

    _moved(roll_back(get_state(ctx).store, _alias_request(model_ref, alias)), as_json)


def _alias_request(model_ref: str, alias: str | None) -> AliasRequest:
    from touchbench.app.cli.requests import build_request
    from touchbench.app.schemas.models import AliasRequest

    return build_request(
        AliasRequest, {"model": "MODEL", "alias": "ALIAS"}, model=model_ref, alias=alias
    )


def _moved(move: AliasMove, as_json: bool) -> None:
    if as_json:
        print_json(move.to_json())
        return
    before = "" if move.previous is None else f" (was version {move.previous})"
    info(f"{move.model.name}@{move.alias} is now version {move.model.version}{before}")
