"""The service side by side with in-process work: prediction latency and throughput over HTTP
against the same model's in-process ``predict_proba``, and a run submitted over HTTP against
the same run from the CLI.

    .venv/bin/python perf/serve.py [--requests 400] [--seconds 10] [--workers 1]
                                   [--client wrk|httpx] [--run-classifiers nb,j48,logistic,rf]
                                   [--classifiers logistic,rf] [--engines native,onnx]

``--engines``: each model's predictions are measured with each engine the request names
(``native``: the model's own estimator; ``onnx``: its ONNX twin in ONNX Runtime, exported
first), beside the same engine in process.

``--workers`` is ``touchbench serve --workers``: service processes sharing the port.
``--client``: the HTTP client that measures. ``wrk`` (Debian's package; the default when it
is installed) is a load generator in C: it takes little of the two cores the service runs on,
so the figures are the service's. ``httpx`` clients in Python threads take about a core of
their own and a millisecond per request: its figures are the service's plus the client's.

Uses Mini (``../shared/datasets``) when present, else a synthetic data set of the same
shape. Prints a table of figures and ratios; nothing here is asserted.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import httpx
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
MINI = ROOT.parent / "shared" / "datasets" / "uc3m-touch" / "mini" / "gesture_and_place.arff"
sys.path.insert(0, str(ROOT))


def percentile(values: list[float], q: float) -> float:
    return float(np.percentile(np.array(values) * 1000.0, q))


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def data_file(folder: Path) -> Path:
    if MINI.exists():
        return MINI
    from tests.support.synthetic import touch_arff

    return touch_arff(folder / "synthetic.arff", n=2777)


def start_service(db: str, folder: Path, workers: int) -> tuple[subprocess.Popen[bytes], str]:
    port = free_port()
    environment = {
        **os.environ,
        "PYTHONPATH": str(ROOT),
        "TOUCHBENCH_WORK_DIR": str(folder / "work"),
        "TOUCHBENCH_JOB_WORKERS": "1",
    }
    command = [
        sys.executable,
        "-m",
        "touchbench.app.cli.main",
        "--db",
        db,
        "serve",
        "--port",
        str(port),
        "--log-level",
        "warning",
        "--workers",
        str(workers),
    ]
    process = subprocess.Popen(command, cwd=ROOT, env=environment)
    return process, wait_until_up(port)


def wait_until_up(port: int) -> str:
    """The URL of the service on ``port`` once ``/healthz`` answers 200 (at most ~2 min)."""
    url = f"http://127.0.0.1:{port}"
    for _ in range(600):
        try:
            if httpx.get(f"{url}/healthz", timeout=1).status_code == 200:
                return url
        except httpx.HTTPError:
            time.sleep(0.2)
    raise SystemExit("the service did not start")


def latency(
    url: str, model: str, record: dict[str, object], n: int, engine: str = "auto"
) -> list[float]:
    times = []
    body = {"instances": [record], "engine": engine}
    # the first request loads the model: minutes on a machine at load 30
    with httpx.Client(base_url=url, timeout=600) as client:
        for _ in range(20):  # warm-up: load the model into the cache, open the connection
            client.post(f"/api/models/{model}/predict", json=body)
        for _ in range(n):
            start = time.perf_counter()
            response = client.post(f"/api/models/{model}/predict", json=body)
            times.append(time.perf_counter() - start)
            assert response.status_code == 200, response.text
    return times


def wrk_script(folder: Path, record: dict[str, object], engine: str = "auto") -> Path:
    """A wrk script that POSTs one instance as JSON."""
    body = json.dumps({"instances": [record], "engine": engine})
    script = folder / "predict.lua"
    script.write_text(
        'wrk.method = "POST"\n'
        'wrk.headers["Content-Type"] = "application/json"\n'
        f"wrk.body = [==[{body}]==]\n"
    )
    return script


def wrk(
    url: str, script: Path, clients: int, seconds: float, *, warm_up: bool = False
) -> tuple[float, float, float]:
    """``wrk`` with ``clients`` connections on one thread: (p50 ms, p99 ms, requests/s).

    ``warm_up``: the first requests of every service process load the model while the
    process still imports its libraries, some for longer than wrk's 2 s timeout; that is
    not counted against the measure.
    """
    # wrk takes whole seconds only (a fraction is a usage error)
    duration = f"-d{max(1, round(seconds))}s"
    done = subprocess.run(
        ["wrk", "-t1", f"-c{clients}", duration, "--latency", "-s", str(script), url],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    if not warm_up and ("Non-2xx" in done or "Socket errors" in done):
        raise SystemExit(f"wrk saw failed requests:\n{done}")

    def milliseconds(percent: str) -> float:
        found = re.search(rf"^\s*{percent}%\s+([\d.]+)(us|ms|s)\s*$", done, re.MULTILINE)
        assert found, done
        scale = {"us": 1e-3, "ms": 1.0, "s": 1e3}[found.group(2)]
        return float(found.group(1)) * scale

    rate = re.search(r"Requests/sec:\s+([\d.]+)", done)
    assert rate, done
    return milliseconds("50"), milliseconds("99"), float(rate.group(1))


def in_process(trained: object, X: np.ndarray, n: int) -> list[float]:
    """Seconds of ``predict_with_proba`` (what a served prediction runs) on ``X``."""
    times = []
    for _ in range(20):
        trained.predict_with_proba(X)  # type: ignore[attr-defined]
    for _ in range(n):
        start = time.perf_counter()
        trained.predict_with_proba(X)  # type: ignore[attr-defined]
        times.append(time.perf_counter() - start)
    return times


def throughput(
    url: str,
    model: str,
    record: dict[str, object],
    clients: int,
    seconds: float,
    engine: str = "auto",
) -> float:
    done = 0
    lock = threading.Lock()
    stop = time.monotonic() + seconds

    def worker() -> None:
        nonlocal done
        with httpx.Client(base_url=url, timeout=60) as client:
            while time.monotonic() < stop:
                response = client.post(
                    f"/api/models/{model}/predict",
                    json={"instances": [record], "engine": engine},
                )
                assert response.status_code == 200
                with lock:
                    done += 1

    threads = [threading.Thread(target=worker) for _ in range(clients)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    return done / seconds


def run_over_http(url: str, request: dict[str, object]) -> tuple[float, int]:
    """Submit the run and poll until it ends: (wall seconds, run id)."""
    with httpx.Client(base_url=url, timeout=60) as client:
        start = time.perf_counter()
        run_id = int(client.post("/api/runs", json=request).json()["id"])
        while client.get(f"/api/runs/{run_id}").json()["status"] in ("queued", "running"):
            time.sleep(0.2)
        return time.perf_counter() - start, run_id


def run_from_cli(db: str, request: dict[str, object]) -> tuple[float, int]:
    """``touchbench bench`` in a new process: (wall seconds, run id)."""
    command = [
        sys.executable,
        "-m",
        "touchbench.app.cli.main",
        "--db",
        db,
        "bench",
        str(request["dataset"]),
        "--target",
        str(request["target"]),
        "-c",
        ",".join(request["classifiers"]),  # type: ignore[arg-type]
        "--folds",
        str(request["folds"]),
        "--json",
    ]
    start = time.perf_counter()
    printed = subprocess.run(command, cwd=ROOT, check=True, capture_output=True, text=True)
    seconds = time.perf_counter() - start
    return seconds, int(json.loads(printed.stdout)["run_id"])


def compare_runs(store: object, url: str, db: str, request: dict[str, object], rounds: int):
    """The same run over HTTP and from the CLI, ``rounds`` times in alternating order.

    Returns rows of the table: wall time, and the part of it the engine ran (the run's
    ``started_at`` to ``finished_at`` in the store); medians of the rounds.
    """
    from touchbench.app.store.runs import get_run

    def executing(run_id: int) -> float:
        run = get_run(store, run_id)  # type: ignore[arg-type]
        assert run.status == "done", (run_id, run.status, run.error)
        assert run.started_at is not None and run.finished_at is not None
        return (run.finished_at - run.started_at).total_seconds()

    walls: dict[str, list[float]] = {"HTTP": [], "CLI": []}
    engine: dict[str, list[float]] = {"HTTP": [], "CLI": []}
    sides = {"HTTP": lambda: run_over_http(url, request), "CLI": lambda: run_from_cli(db, request)}
    for number in range(rounds):
        for side in ("HTTP", "CLI") if number % 2 == 0 else ("CLI", "HTTP"):
            seconds, run_id = sides[side]()
            walls[side].append(seconds)
            engine[side].append(executing(run_id))
            print(
                f"round {number + 1}, {side}: {seconds:.1f} s, {engine[side][-1]:.1f} s in the "
                f"engine",
                file=sys.stderr,
            )
    ratio = statistics.median(h / c for h, c in zip(walls["HTTP"], walls["CLI"], strict=True))
    engine_ratio = statistics.median(
        h / c for h, c in zip(engine["HTTP"], engine["CLI"], strict=True)
    )
    label = f"run {','.join(request['classifiers'])} x {request['folds']} folds"  # type: ignore[arg-type]
    return [
        (
            f"{label}, wall (s)",
            f"HTTP {statistics.median(walls['HTTP']):.1f}",
            f"CLI {statistics.median(walls['CLI']):.1f}",
            f"ratio {ratio:.3f}",
        ),
        (
            f"{label}, in the engine (s)",
            f"HTTP {statistics.median(engine['HTTP']):.1f}",
            f"CLI {statistics.median(engine['CLI']):.1f}",
            f"ratio {engine_ratio:.3f}",
        ),
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--requests", type=int, default=400)
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--workers", type=int, default=1, help="service processes")
    parser.add_argument(
        "--rounds",
        type=int,
        default=5,
        help="alternations of in-process and HTTP measures (medians are shown)",
    )
    parser.add_argument(
        "--run-classifiers",
        default="nb,j48,logistic,rf",
        help="the run compared over HTTP and from the CLI ('' leaves it out)",
    )
    parser.add_argument(
        "--run-rounds",
        type=int,
        default=3,
        help="runs on each side, in alternating order (medians are shown)",
    )
    parser.add_argument(
        "--no-predictions",
        action="store_true",
        help="leave the prediction latency and throughput out (the run comparison only)",
    )
    parser.add_argument(
        "--classifiers", default="logistic,rf", help="models whose predictions are measured"
    )
    parser.add_argument(
        "--engines", default="native,onnx", help="engines each model's predictions run with"
    )
    parser.add_argument(
        "--client",
        choices=("wrk", "httpx"),
        default="wrk" if shutil.which("wrk") else "httpx",
        help="the measuring client (default: wrk when installed)",
    )
    args = parser.parse_args()

    from touchbench.app.schemas.datasets import ImportRequest
    from touchbench.app.schemas.models import ExportRequest, TrainRequest
    from touchbench.app.services.alignment import align_features
    from touchbench.app.services.datasets import import_file
    from touchbench.app.services.export import export_model
    from touchbench.app.services.loading import load_predictor
    from touchbench.app.services.models import train
    from touchbench.app.store.database import Store
    from touchbench.benchmark.io import read_arff

    folder = Path(tempfile.mkdtemp(prefix="touchbench-serve-perf-"))
    db = f"sqlite:///{folder / 'perf.db'}"
    store = Store(db)
    source = data_file(folder)
    imported = import_file(store, ImportRequest(file=source, name="mini"))
    classifiers = args.classifiers.split(",")
    engines = args.engines.split(",")
    for classifier in classifiers:
        train(
            store,
            TrainRequest(
                dataset="mini", classifier=classifier, target="gesture", name=f"mini-{classifier}"
            ),
        )
        if "onnx" in engines:
            export_model(store, ExportRequest(model=f"mini-{classifier}"))
    data = read_arff(source)
    process, url = start_service(db, folder, args.workers)
    rows = []
    try:
        measured = [(c, e) for c in classifiers for e in engines]
        for classifier, engine in [] if args.no_predictions else measured:
            info, trained = load_predictor(store, f"mini-{classifier}", engine)  # type: ignore[arg-type]
            X = align_features(trained.schema, data)[:1]
            record: dict[str, object] = {
                attribute.name: (
                    None
                    if not np.isfinite(value)
                    else attribute.label(value)
                    if attribute.kind == "nominal"
                    else float(value)
                )  # a nominal attribute by its label, as a client sends it
                for attribute, value in zip(trained.schema.features, X[0], strict=True)
            }
            path = f"{url}/api/models/{info.name}/predict"
            latency(url, info.name, record, 20, engine)  # load the model, open a connection
            if args.client == "wrk":
                script = wrk_script(folder, record, engine)
                wrk(path, script, 8, 5.0, warm_up=True)  # every service process loads the model
            # Rounds of in-process then HTTP, so that both see the machine in the same state
            # (its speed drifts by a third from minute to minute here); medians of the rounds.
            local, remote = [], []
            for _ in range(args.rounds):
                times = in_process(trained, X, args.requests)
                local.append((percentile(times, 50), percentile(times, 99)))
                if args.client == "wrk":
                    p50, p99, _ = wrk(path, script, 1, args.seconds / args.rounds)
                else:
                    http_times = latency(url, info.name, record, args.requests, engine)
                    p50, p99 = percentile(http_times, 50), percentile(http_times, 99)
                remote.append((p50, p99))
            p50, p99 = (statistics.median(r[k] for r in remote) for k in (0, 1))
            l50, l99 = (statistics.median(r[k] for r in local) for k in (0, 1))
            overhead = statistics.median(r[0] - q[0] for r, q in zip(remote, local, strict=True))
            rows.append(
                (
                    f"{classifier} ({engine}) one instance: HTTP p50 / p99 (ms)",
                    f"{p50:.2f} / {p99:.2f}",
                    f"in-process {l50:.2f} / {l99:.2f}",
                    f"overhead p50 {overhead:.2f} ms",
                )
            )
            for clients in (8, 32):
                local_rates, rates = [], []
                for _ in range(args.rounds):
                    local_rates.append(1.0 / statistics.mean(in_process(trained, X, args.requests)))
                    seconds = args.seconds / args.rounds
                    if args.client == "wrk":
                        rates.append(wrk(path, script, clients, seconds)[2])
                    else:
                        rates.append(throughput(url, info.name, record, clients, seconds, engine))
                ratio = statistics.median(r / q for r, q in zip(rates, local_rates, strict=True))
                rows.append(
                    (
                        f"{classifier} ({engine}) throughput, {clients} clients (req/s)",
                        f"{statistics.median(rates):.0f}",
                        f"in-process {statistics.median(local_rates):.0f}",
                        f"ratio {ratio:.2f}",
                    )
                )
        if args.run_classifiers:
            request = {
                "dataset": "mini",
                "target": "gesture",
                "classifiers": args.run_classifiers.split(","),
                "folds": 10,
            }
            rows += compare_runs(store, url, db, request, args.run_rounds)
    finally:
        process.terminate()
        process.wait(timeout=30)
        store.dispose()
    print(
        f"data: {source} ({imported.n_instances} instances); {args.workers} service "
        f"process(es); client {args.client}; load {os.getloadavg()[0]:.1f}"
    )
    width = max(len(row[0]) for row in rows)
    for row in rows:
        print(f"{row[0]:<{width}}  {row[1]:>16}  {row[2]:>22}  {row[3]}")


if __name__ == "__main__":
    main()
