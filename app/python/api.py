"""``touchbench.bench``, ``touchbench.extract`` and ``touchbench.train``: the CLI's verbs in a
researcher's own Python, over the same request types and services.

Each call builds the request the CLI would build (:class:`app.schemas.runs.BenchRequest`,
:class:`app.schemas.extraction.ExtractRequest`, :class:`app.schemas.models.TrainRequest`),
so that every default, bound and rule is the one the CLI and the service apply, and a
refused field is one :class:`app.errors.FieldError` naming it.  What was made is kept in
``store``: the caller's (a URL, or a path to a SQLite file, that ``touchbench --db`` and
``touchbench serve`` read), or a temporary one for the Python session.
"""

from __future__ import annotations

# Imports inside functions: start-up time: the simulators load with the first simulate().
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

from pydantic import ValidationError

from touchbench.app.errors import FieldError
from touchbench.app.python.data import frame_of, stored_data
from touchbench.app.python.estimators import Classifier, classifier_choice
from touchbench.app.python.leaderboard import Leaderboard
from touchbench.app.python.model import Model
from touchbench.app.python.progress import RunBar
from touchbench.app.python.sources import stored_leaderboard
from touchbench.app.python.stores import StoreLike, open_store
from touchbench.app.schemas.base import Request, field_error
from touchbench.app.schemas.extraction import ExtractRequest
from touchbench.app.schemas.models import TrainRequest
from touchbench.app.schemas.runs import BenchHereRequest, BenchRequest
from touchbench.app.services.bench import bench_here
from touchbench.app.services.datasets import delete_dataset, read_dataset
from touchbench.app.services.extraction import extract_and_store
from touchbench.app.services.models import check_training
from touchbench.app.services.models import train as train_model
from touchbench.app.services.own_specs import own_specs_added
from touchbench.app.services.runs import create_run
from touchbench.app.store.database import Store

if TYPE_CHECKING:
    import pandas as pd


def bench(
    data: Any,
    *,
    target: str | None = None,
    classifiers: str | Sequence[Classifier] = "fast",
    folds: int | str = 10,
    repeats: int = 1,
    seed: int = 0,
    groups: str | None = None,
    ignore: Sequence[str] = (),
    metric: str | None = None,
    race: bool = False,
    jobs: int = 1,
    store: StoreLike = None,
    progress: bool = True,
) -> Leaderboard:
    """Cross-validate classifiers on ``data`` and rank them, as ``touchbench bench`` does.

    Parameters
    ----------
    data : DataFrame, (X, y), str or Path
        A DataFrame; arrays ``X`` of shape (n_instances, n_features) and ``y`` of shape
        (n_instances,); an ARFF or CSV file; or the name of a data set in ``store``.
    target : str, optional
        The column to predict (required with a DataFrame; ``y`` for a pair; default for a
        file or a stored data set: its own targets).
    classifiers : str or list
        A suite (``fast``, ``default``, ``all``), or a list mixing catalogue ids
        (``"rf"``), scikit-learn estimators (named by their class) and ``(name,
        estimator)`` pairs.
    folds : int or "logo"
        k of k-fold, or ``"logo"`` (leave-one-group-out: one fold per group).
    repeats, seed, metric, race
        As ``touchbench bench``'s options.
    groups : str, optional
        The column naming each row's group (object, subject, session): folds keep a group
        on one side, and it is never a feature.
    ignore : sequence of str
        Columns left out.
    jobs : int
        Worker processes.
    store : Store, str, Path or None
        Where the data set and the run are kept (see the module's notes).
    progress : bool
        Show a progress bar (a widget in Jupyter).

    Returns
    -------
    Leaderboard

    Raises
    ------
    FieldError
        A refused field (its ``field`` names it); nothing is stored.
    KeyboardInterrupt
        Interrupted (Ctrl-C, the notebook's stop): the run is kept as ``interrupted`` with
        its finished folds, which ``touchbench bench --resume RUN`` finishes.
    """
    suite, ids, specs = classifier_choice(classifiers)
    opened = open_store(store)
    with own_specs_added(specs):
        # the request first: a refused field stores nothing, not even the data set
        _request(BenchRequest, dataset="-", classifiers=ids or None, suite=suite, folds=folds,
                 repeats=repeats, seed=seed, metric=metric, race=race)  # fmt: skip
        name, created = stored_data(opened, data, target=target, groups=groups, ignore=ignore)
        with _kept_if_used(opened, name, created):
            request = _request(
                BenchRequest,
                dataset=name,
                target=target if _names_target(data) else None,
                classifiers=ids or None,
                suite=suite,
                folds=folds,
                repeats=repeats,
                seed=seed,
                metric=metric,
                race=race,
            )
            run = create_run(opened, request, on_warning=RunBar.warn)
        with RunBar(show=progress) as bar:  # closed on an interrupt too (RunInterrupted)
            benched = bench_here(
                opened, BenchHereRequest(resume=run.id), jobs=jobs, callbacks=bar.callbacks()
            )
    assert benched.run is not None
    return stored_leaderboard(opened, benched.run.id)


def extract(
    recordings: str | Path | Sequence[str | Path],
    *,
    labels: str | Path | None = None,
    extractor: str | None = None,
    name: str | None = None,
    store: StoreLike = None,
    **options: Any,
) -> pd.DataFrame:
    """Turn recordings into a labelled table, as ``touchbench extract`` does, and keep it
    in ``store`` as a data set (its recordings are its groups).

    Parameters
    ----------
    recordings : path or sequence of paths
        Audio files, CSV time series, ``.npy`` files or ROS bags; a folder means every file
        in it.
    labels : path, optional
        The labels CSV (``file,start,end,TARGET...``).
    extractor : str, optional
        A feature extractor (``touchbench extractors`` lists them).
    name : str, optional
        The data set's name in the store.
    **options
        Fields of the extraction request (``events``, ``samplerate``, ``segment``...);
        others are options of the extractor and the event detector.

    Returns
    -------
    pandas.DataFrame of shape (n_events, n_features + n_targets + 1)
        The features, the targets and each event's recording in a column ``group``
        (``df.attrs["dataset"]`` names the stored data set).
    """
    paths = _recording_paths(recordings)
    fields = set(ExtractRequest.model_fields)
    given = {k: v for k, v in options.items() if k in fields}
    rest = {k: v for k, v in options.items() if k not in fields}
    opened = open_store(store)
    request = _request(
        ExtractRequest,
        recordings=paths,
        labels=None if labels is None else Path(labels),
        name=name,
        **({"extractor": extractor} if extractor else {}),
        **({"options": rest} if rest else {}),
        **given,
    )
    summary = extract_and_store(opened, request)
    frame = frame_of(read_dataset(opened, summary.id))
    frame.attrs["dataset"] = summary.name
    return frame


def simulate(
    out: str | Path,
    sensor: Literal["contact-mic", "oscillating-link"] = "contact-mic",
    *,
    trials: int = 3,
    seed: int = 0,
    touches: int = 16,
) -> tuple[list[Path], Path]:
    """Write simulated recordings and their labels CSV, as ``touchbench simulate`` does.

    Parameters
    ----------
    out : path
        The folder (made if missing).
    sensor : {"contact-mic", "oscillating-link"}
        Sessions of taps and strokes on three contact microphones (extract them with
        ``extractor="uc3m-audio"``), or trials of a shaken link with an accelerometer
        (``extractor="band-peaks"``).
    trials : int
        Sessions or trials.
    seed : int
        Seed of every random draw.
    touches : int
        Touches per contact-microphone session.

    Returns
    -------
    recordings : list of Path
    labels : Path
    """
    from touchbench.app.services.simulation import write_contact_mic_sessions, write_link_trials

    if trials < 1:
        raise FieldError("trials", f"must be at least 1, got {trials}")
    if sensor == "contact-mic":
        if touches < 1:
            raise FieldError("touches", f"must be at least 1, got {touches}")
        return write_contact_mic_sessions(Path(out), trials=trials, seed=seed, n_touches=touches)
    if sensor == "oscillating-link":
        return write_link_trials(Path(out), trials=trials, seed=seed)
    raise FieldError("sensor", f"must be contact-mic or oscillating-link, got '{sensor}'")


def train(
    data: Any = None,
    *,
    target: str | None = None,
    classifier: str | None = None,
    name: str | None = None,
    seed: int = 0,
    groups: str | None = None,
    ignore: Sequence[str] = (),
    store: StoreLike = None,
) -> Model:
    """Fit a classifier on every row of ``data`` and keep it as a model, as ``touchbench
    train`` does; or, with a :class:`Leaderboard` as ``data``, its run's best classifier
    (or ``classifier``, one of its rows) on the run's data set.

    Parameters
    ----------
    data : DataFrame, (X, y), path, stored name or Leaderboard
        As :func:`bench` takes it.
    target, groups, ignore, store
        As :func:`bench` takes them.
    classifier : str, optional
        A catalogue id (required unless ``data`` is a leaderboard).  Estimators of the
        caller's own are benchmarked, not trained: models are kept in a format that runs
        no code, which knows the catalogue's classifiers only.
    name : str, optional
        The model's name (default ``DATASET-CLASSIFIER``); each call adds a version.
    seed : int
        Seed of the classifier.

    Returns
    -------
    Model
    """
    if isinstance(data, Leaderboard) and classifier is None:
        opened = open_store(store if store is not None else _leaderboard_store(data))
        request = _request(TrainRequest, run=data.run_id, name=name)
    elif isinstance(data, Leaderboard) and classifier is not None:  # one of its rows
        opened = open_store(store if store is not None else _leaderboard_store(data))
        data.row(classifier)  # one of the run's
        targets = data.schema.targets
        request = _request(
            TrainRequest,
            dataset=data.schema.dataset,
            classifier=classifier,
            target=targets[0] if len(targets) == 1 else None,
            name=name,
            seed=seed,
        )
    else:
        if classifier is None:
            raise FieldError("classifier", "is required (or a leaderboard, for its best)")
        opened = open_store(store)
        _request(TrainRequest, dataset="-", classifier=classifier, name=name, seed=seed)
        dataset, created = stored_data(opened, data, target=target, groups=groups, ignore=ignore)
        with _kept_if_used(opened, dataset, created):
            request = _request(
                TrainRequest,
                dataset=dataset,
                classifier=classifier,
                target=target if _names_target(data) else None,
                name=name,
                seed=seed,
            )
            check_training(opened, request)
    return Model(train_model(opened, request), opened)


# ----------------------------------------------------------------------------- inside


def _request(kind: type[Request], **values: Any) -> Any:
    """``kind`` made of ``values`` (``None`` left to the request's default); the first
    field it refuses as a :class:`FieldError`."""
    try:
        return kind(**{k: v for k, v in values.items() if v is not None})
    except ValidationError as error:
        raise field_error(error) from None


@contextmanager
def _kept_if_used(store: Store, dataset: str, created: bool) -> Iterator[None]:
    """Remove the data set this call stored if what it was stored for is refused: a
    refused call leaves nothing behind."""
    try:
        yield
    except BaseException:
        if created:
            delete_dataset(store, dataset)
        raise


def _names_target(data: Any) -> bool:
    """Whether ``target`` picks one target among a stored data set's (a file or a stored
    name), rather than naming the one column of a DataFrame stored with it alone."""
    return isinstance(data, str | Path)


def _recording_paths(recordings: str | Path | Sequence[str | Path]) -> list[Path]:
    items = [recordings] if isinstance(recordings, str | Path) else list(recordings)
    paths: list[Path] = []
    for item in items:
        path = Path(item).expanduser()
        paths.extend(sorted(p for p in path.iterdir() if p.is_file()) if path.is_dir() else [path])
    return paths


def _leaderboard_store(board: Leaderboard) -> Any:
    source = board._source
    return getattr(source, "store", None)
