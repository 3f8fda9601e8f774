"""Commands for models: train, models, predict."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from app.cli.output import info, print_json, table
from app.cli.state import get_state
from app.services.datasets import guess_format
from app.store.models import list_models
from benchmark.errors import DataFormatError
from benchmark.io.arff import read_arff
from benchmark.io.csv import read_csv

JsonOption = Annotated[bool, typer.Option("--json", help="Print only JSON on stdout.")]


def register(app: typer.Typer) -> None:
    app.command("train")(train_command)
    app.command("models")(models_command)
    app.command("predict")(predict_command)


def train_command(
    ctx: typer.Context,
    dataset: Annotated[str, typer.Argument(metavar="DATASET", help="Data set name or id.")],
    classifier: Annotated[
        str,
        typer.Option("--classifier", "-c", help="Classifier id (see `touchbench classifiers`)."),
    ],
    target: Annotated[
        str | None, typer.Option("--target", help="Train for this one target only.")
    ] = None,
    name: Annotated[str | None, typer.Option("--name", help="Model name.")] = None,
    seed: Annotated[int, typer.Option("--seed", help="Seed of the classifier.")] = 0,
    as_json: JsonOption = False,
) -> None:
    """Fit a classifier on every instance of a data set and store the model."""
    from app.services.models import train

    model = train(
        get_state(ctx).store,
        dataset,
        classifier,
        targets=[target] if target else None,
        name=name,
        seed=seed,
    )
    if as_json:
        print_json(model.to_json())
        return
    info(
        f"trained model {model.id} '{model.name}': {model.classifier} on {model.dataset_name} "
        f"for {', '.join(model.targets)} ({model.size_bytes:,} bytes, sha256 {model.sha256[:12]})"
    )


def models_command(ctx: typer.Context, as_json: JsonOption = False) -> None:
    """List trained models."""
    models = list_models(get_state(ctx).store)
    if as_json:
        print_json({"models": [m.to_json() for m in models]})
        return
    if not models:
        info("no models yet: `touchbench train DATASET --classifier ID` makes one")
        return
    table(
        None,
        ["id", "name", "classifier", "dataset", "targets", "bytes", "trained"],
        [
            (
                m.id,
                m.name,
                m.classifier,
                m.dataset_name,
                ", ".join(m.targets),
                f"{m.size_bytes:,}",
                m.created_at.strftime("%Y-%m-%d %H:%M"),
            )
            for m in models
        ],
    )


def predict_command(
    ctx: typer.Context,
    model_ref: Annotated[str, typer.Argument(metavar="MODEL", help="Model name or id.")],
    file: Annotated[Path, typer.Argument(help="ARFF or CSV file with the model's attributes.")],
    as_json: JsonOption = False,
) -> None:
    """Predict every instance of a file; attributes are matched to the model's by name."""
    from app.services.models import load_model, predict

    model_info, model = load_model(get_state(ctx).store, model_ref)
    if not file.exists():
        raise DataFormatError("no such file", source=str(file))
    data = read_csv(file, targets=None) if guess_format(file) == "csv" else read_arff(file)
    predictions = predict(model, data, source=str(file))
    if as_json:
        print_json(
            {
                "model": model_info.name,
                "targets": model_info.targets,
                "predictions": predictions.to_json(),
                "accuracy": predictions.accuracy,
            }
        )
        return
    rows = predictions.to_json()
    columns = ["#", *model_info.targets]
    if predictions.probabilities is not None:
        columns += [f"p({t})" for t in model_info.targets]
    table(
        f"{len(rows)} predictions by {model_info.name}",
        columns,
        [
            (
                row["instance"],
                *(row[t] for t in model_info.targets),
                *(
                    f"{row['probabilities'][t][row[t]]:.3f}"
                    for t in model_info.targets
                    if "probabilities" in row
                ),
            )
            for row in rows
        ],
    )
    for target, accuracy in predictions.accuracy.items():
        info(f"accuracy on {target} (the file carries the true labels): {accuracy:.4f}")
