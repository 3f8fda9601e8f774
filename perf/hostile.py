"""Hostile clients (issue 36): each case of the issue replayed against a real service, with
the service's peak memory and another client's one-instance prediction latency during it
(that client in a process of its own), beside the same latency on the idle service just
before (the two windows alternate).

    .venv/bin/python perf/hostile.py [--quick] [--seconds 8] [--db URL] [--only pages] [--pace 0.5]
                                     [--split]

Goal: every case under 300 MB over idle and its p99 within 2x of the idle p99.  Memory is
the service process's resident set sampled every 10 ms during the case (its growth over
the idle service) and its ``VmHWM`` after it (which only grows, so a case inherits the
peaks of those before it).  The cases other parts of the work fix (a deleted version that
comes back, three concurrent ONNX twin requests, keys in the debug log, the alias race)
are replayed too, and their ``verdict`` says whether the service behaved.  Nothing here is
asserted; ``--quick`` shortens the windows and shrinks the largest inputs (the labels file,
the sequence upload) for a first look.

``--split`` measures the deployment that keeps robots apart from the store's managers: a
second process, ``touchbench serve --predictions-only``, on the same store answers the
measuring client and every prediction request of the cases (their other requests go to the
full service); memory is then the two processes' together.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import contextlib
import multiprocessing
import os
import re
import secrets
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from multiprocessing.connection import Connection
from pathlib import Path

import httpx

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from perf.serve import free_port, percentile, wait_until_up  # noqa: E402 (after the path)
from perf.trust_load import peak_rss_mb, train, upload  # noqa: E402
from tests.support import hostile_inputs as hostile  # noqa: E402
from tests.support.synthetic import touch_arff  # noqa: E402

GOAL_MB = 300
GOAL_RATIO = 2.0
#: A row that measures the load of a case without its harm (what the machine's cores cost).
CONTROL = "control:"
RECORD = {"f0": 0.1, "f1": 0.2, "f2": -0.3, "f3": 1.0, "mic": "left"}
#: The paths a predictions-only process answers that the cases ask.
PREDICTION_PATH = re.compile(r"^/api/models/[^/]+/predict(/file)?$")


def start_service(
    db: str,
    folder: Path,
    *,
    log: Path | None = None,
    level: str = "warning",
    options: tuple[str, ...] = (),
    **settings: str,
) -> tuple[subprocess.Popen[bytes], str]:
    port = free_port()
    environment = {
        **os.environ,
        "PYTHONPATH": str(ROOT),
        "TOUCHBENCH_WORK_DIR": str(folder / "work"),
        "TOUCHBENCH_JOB_WORKERS": "1",
        **{f"TOUCHBENCH_{key.upper()}": value for key, value in settings.items()},
    }
    command = [sys.executable, "-m", "touchbench.app.cli.main", "--db", db, "serve"]
    output = log.open("ab") if log is not None else None
    process = subprocess.Popen(
        [*command, "--port", str(port), "--log-level", level, *options],
        cwd=ROOT,
        env=environment,
        stdout=output,
        stderr=subprocess.STDOUT if output else None,
        start_new_session=True,
    )
    return process, wait_until_up(port)


def rss_mb(pids: list[int]) -> float:
    """The processes' resident sets together (MB)."""
    total = 0.0
    for pid in pids:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                total += int(line.split()[1]) / 1024
    return total


def hwm_mb(pids: list[int]) -> float:
    """The processes' peak resident sets (``VmHWM``) together (MB)."""
    return sum(peak_rss_mb(pid) for pid in pids)


class ToPredictions(httpx.HTTPTransport):
    """Sends the prediction requests to a predictions-only process (another port of this
    host), the rest where the client's base URL says."""

    def __init__(self, predictions_url: str) -> None:
        super().__init__()
        self._port = httpx.URL(predictions_url).port

    def handle_request(self, request: httpx.Request) -> httpx.Response:
        if PREDICTION_PATH.match(request.url.path):
            request.url = request.url.copy_with(port=self._port)
        return super().handle_request(request)


@dataclass
class Window:
    """What one window measured: the other client's latencies (s), the statuses of the
    case's requests, the service's largest resident set sampled (MB), and what the case
    said of itself."""

    latencies: list[float]
    statuses: list[int]
    peak_mb: float
    verdict: str = ""


class Prober:
    """Another client's one-instance predictions, from a process of its own: in a thread of
    this one, it would wait for this process's GIL while a case's client builds or reads a
    large body, and time this process, not the service."""

    def __init__(self, url: str, model: int) -> None:
        context = multiprocessing.get_context("spawn")
        self._connection, child = context.Pipe()
        self._process = context.Process(target=_probe, args=(url, model, child), daemon=True)
        self._process.start()

    def start(self) -> None:
        self._connection.send("start")

    def stop(self) -> list[float]:
        """The latencies (s) since :meth:`start`."""
        self._connection.send("stop")
        said, value = self._connection.recv()
        if said != "ok":
            raise RuntimeError(f"a prediction failed: {value}")
        return list(value)

    def close(self) -> None:
        self._connection.send("quit")
        self._process.join(timeout=30)


def _probe(url: str, model: int, connection: Connection) -> None:
    with httpx.Client(base_url=url, timeout=120) as client:
        while connection.recv() == "start":
            latencies: list[float] = []
            failed = None
            while not connection.poll():
                start = time.perf_counter()
                answer = client.post(f"/api/models/{model}/predict", json={"instances": [RECORD]})
                latencies.append(time.perf_counter() - start)
                if answer.status_code != 200 and failed is None:
                    failed = answer.text[:300]
            connection.recv()  # "stop"
            connection.send(("ok", latencies) if failed is None else ("error", failed))


def window(
    prober: Prober, pids: list[int], seconds: float, work: Callable[[], object] | None = None
) -> Window:
    """Another client's predictions for ``seconds`` (at least while ``work`` runs once),
    with ``work`` replayed meanwhile when given; the service's processes are ``pids``."""
    stop = threading.Event()
    peak = [rss_mb(pids)]

    def sample() -> None:
        while not stop.is_set():
            peak[0] = max(peak[0], rss_mb(pids))
            time.sleep(0.01)

    sampler = threading.Thread(target=sample, daemon=True)
    sampler.start()
    prober.start()
    statuses: list[int] = []
    verdicts: list[str] = []
    deadline = time.monotonic() + seconds
    try:
        while True:
            if work is not None:
                said = work()
                said = said if isinstance(said, tuple) else (said,)
                statuses += [s for s in said if isinstance(s, int)]
                verdicts += [s for s in said if isinstance(s, str)]
            else:
                time.sleep(0.05)
            if time.monotonic() >= deadline:
                break
    finally:
        latencies = prober.stop()
        stop.set()
        sampler.join()
    return Window(latencies, statuses, peak[0], verdicts[-1] if verdicts else "")


def once(replay: Callable[[], object]) -> Callable[[], object]:
    """``replay`` carried out the first time only (a case whose repetition would measure
    something else: a twin already stored, a version already deleted); the window then
    waits out its time."""
    done: list[object] = []

    def first() -> object:
        if done:
            time.sleep(0.05)
            return ()
        done.append(replay())
        return done[0]

    return first


def paced(replay: Callable[[], object], seconds: float) -> Callable[[], object]:
    """``replay`` taking at least ``seconds`` (it sleeps the rest): a case then asks at one
    rate whatever a version of the service answers in, and the measuring client's p99
    compares the service's cost, not how fast the hostile client can ask."""

    def at_pace() -> object:
        start = time.monotonic()
        said = replay()
        time.sleep(max(0.0, seconds - (time.monotonic() - start)))
        return said

    return at_pace


def post_file(client: httpx.Client, path: str, file: Path, **data: str) -> int:
    with file.open("rb") as handle:
        return client.post(path, files={"file": (file.name, handle)}, data=data).status_code


def session_upload(client: httpx.Client, recordings: list[Path], labels: Path, **form: str) -> int:
    """The files streamed from disk: read whole into this process, their copies would hold
    its GIL, and the measuring client's thread would wait on this one, not on the service."""
    with contextlib.ExitStack() as stack:
        files = [
            (field, (path.name, stack.enter_context(path.open("rb"))))
            for field, path in [*(("recordings", p) for p in recordings), ("labels", labels)]
        ]
        return client.post("/api/datasets/recordings", files=files, data=form).status_code


def wait_job(client: httpx.Client, job: int) -> dict[str, object]:
    while True:
        body: dict[str, object] = client.get(f"/api/jobs/{job}").json()
        if body["status"] not in ("queued", "running"):
            return body
        time.sleep(0.2)


def train_named(client: httpx.Client, dataset: str, classifier: str, name: str) -> dict:
    answer = client.post(
        "/api/models", json={"dataset": dataset, "classifier": classifier, "name": name}
    )
    assert answer.status_code == 202, answer.text
    body = wait_job(client, answer.json()["job"])
    assert body["status"] == "done", body
    return client.get(f"/api/models/{name}@latest").json()


def extract_takes(db: str, folder: Path) -> None:
    """Timed CSV recordings extracted into ``takes``: a model with a recipe predicts CSV
    files as recordings."""
    recordings, labels = hostile.timed_takes(folder / "takes")
    options = "-e sequence --events none --segment 0.05 -O length=50 --name takes"
    command = [sys.executable, "-m", "touchbench.app.cli.main", "--db", db, "extract"]
    subprocess.run(
        [*command, *map(str, recordings), "--labels", str(labels), *options.split()],
        cwd=ROOT,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        check=True,
        capture_output=True,
    )


# -- the cases -----------------------------------------------------------------------------


def issue_cases(
    client: httpx.Client, folder: Path, quick: bool
) -> list[tuple[str, Callable[[], object]]]:
    """The cases this branch fixes, as ``(name, replay)``; the replay returns the status
    of each request it made."""
    gap, far = hostile.gap_csv(folder / "gap.csv"), hostile.gap_csv(folder / "far.csv", jump=1e6)
    nan = hostile.nan_stamp_csv(folder / "nan.csv")
    one_line = hostile.one_line_csv(folder / "one-line.csv", megabytes=20)
    take = hostile.timed_takes(folder / "one-take", n_takes=1)[0][0]
    labels_rows = 300_000 if quick else 3_000_000  # 8 MB or 80 MB
    labels = hostile.long_labels(folder / "labels.csv", n_rows=labels_rows)
    deep = hostile.deep_json(100_000)
    predict_file = "/api/models/takes-nb/predict/file"
    json_headers = {"content-type": "application/json"}

    return [
        ("150-byte CSV, stamps jump 3,000 s", lambda: post_file(client, predict_file, gap)),
        ("... jump 10^6 s", lambda: post_file(client, predict_file, far)),
        ("NaN stamp", lambda: post_file(client, predict_file, nan)),
        ("20 MB CSV of one line", lambda: post_file(client, predict_file, one_line)),
        (
            f"labels CSV of {labels.stat().st_size / 2**20:.0f} MB",
            lambda: session_upload(client, [take], labels, extractor="window"),
        ),
        (
            "100,000-deep JSON body",
            lambda: (
                client.post(
                    "/api/models/takes-nb/predict", content=deep, headers=json_headers
                ).status_code
            ),
        ),
        (
            "name with U+202E",
            lambda: (
                client.post(
                    "/api/datasets/touch/rename", json={"name": hostile.RLO_NAME}
                ).status_code
            ),
        ),
    ]


def run_pages(client: httpx.Client, folder: Path) -> list[tuple[str, Callable[[], object]]]:
    """The page and fragments of an imported run of 3,000 classifiers.  The first request
    of the leaderboard and of the plots ranks the run (once per version of its results,
    kept for the next): its window holds that one computation and the kept answers."""
    paper = touch_arff(folder / "paper.arff", n=90, with_place=False)
    assert post_file(client, "/api/datasets", paper, name="paper") == 201
    results = hostile.results_arff(folder / "results.arff", n_classifiers=3000)
    with results.open("rb") as handle:
        run = client.post(
            "/api/runs/import-results",
            files={"file": (results.name, handle)},
            data={"dataset": "paper"},
        ).json()["id"]
    return [
        (
            "3,000-classifier run, leaderboard",
            lambda: client.get(f"/fragments/runs/{run}/leaderboard").status_code,
        ),
        (
            "3,000-classifier run, plots",
            lambda: client.get(f"/fragments/runs/{run}/plots").status_code,
        ),
        (
            "3,000-classifier run, page and progress",
            lambda: (
                client.get(f"/runs/{run}").status_code,
                client.get(f"/fragments/runs/{run}/progress").status_code,
            ),
        ),
    ]


def sequences_case(
    client: httpx.Client, folder: Path, quick: bool
) -> tuple[str, Callable[[], object]]:
    """Whole BioTac-like recordings uploaded and extracted as sequences, default limits."""
    n = 50 if quick else 200
    recordings, labels = hostile.tactile_sequences(folder / "biotac", n_recordings=n)

    def replay() -> object:
        files = [("recordings", (p.name, p.read_bytes())) for p in recordings]
        files.append(("labels", (labels.name, labels.read_bytes())))
        form = {"extractor": "sequence", "events": "none", "samplerate": "100", "name": "biotac"}
        answer = client.post("/api/datasets/recordings", files=files, data=form)
        if answer.status_code != 202:
            return answer.status_code, f"refused: {answer.text[:120]}"
        body = wait_job(client, answer.json()["job"])
        return answer.status_code, f"job {body['status']}"

    return f"44 x 800 x {n} sequences extracted", once(replay)


def others_cases(
    client: httpx.Client, db: str, folder: Path
) -> list[tuple[str, Callable[[], object]]]:
    """The cases other parts of the work fix: they may fail here until those are merged."""
    for _ in range(2):
        train_named(client, "touch", "nb", "pin")
    client.post("/api/models/pin@2/promote")

    def deleted_version() -> object:
        gone = client.delete("/api/models/pin@latest").json()
        again = train_named(client, "touch", "j48", "pin")
        rolled = client.post("/api/models/pin/rollback")
        back = again["version"] == gone["version"] or again["id"] == gone["id"]
        onto = rolled.status_code == 200 and rolled.json().get("version") == again["version"]
        verdict = "FAIL: the deleted version came back" if back else "ok: a new version"
        if onto:
            verdict += "; rollback moved @champion onto it"
        return rolled.status_code, verdict

    twin = train_named(client, "touch", "rf", "twin")

    def twin_requests() -> object:
        def get() -> int:
            with httpx.Client(base_url=str(client.base_url), timeout=600) as other:
                return other.get(f"/api/models/{twin['id']}/onnx").status_code

        with concurrent.futures.ThreadPoolExecutor(3) as pool:
            statuses = list(pool.map(lambda _: get(), range(3)))
        converted = "converted in the request" if 200 in statuses else "a job"
        return (*statuses, f"{'FAIL' if 200 in statuses else 'ok'}: {converted}")

    # one client per thread, made once: a client made per request would spend this process's
    # CPU on its TLS context (certificates loaded even for plain HTTP), which shares the cores
    # with the service and the measuring client, and time that rather than the service
    racers = [httpx.Client(base_url=str(client.base_url), timeout=60) for _ in range(4)]

    def alias_race() -> object:
        def flip(index: int) -> int:
            other = racers[index % 4]
            if index % 2:
                return other.delete("/api/models/pin@1/aliases/race").status_code
            return other.post("/api/models/pin@1/aliases", json={"alias": "race"}).status_code

        with concurrent.futures.ThreadPoolExecutor(4) as pool:
            statuses = list(pool.map(flip, range(40)))
        errors = statuses.count(500)
        return (*statuses, f"{'FAIL' if errors else 'ok'}: {errors} answered 500")

    def reads_from_4_threads() -> object:
        """The race's load without its writes: what 4 clients asking back to back cost
        the measuring client whatever they ask."""
        with concurrent.futures.ThreadPoolExecutor(4) as pool:
            return tuple(
                pool.map(
                    lambda index: racers[index % 4].get("/api/models/pin@1").status_code, range(40)
                )
            )

    def keys_in_log() -> object:
        key = "k" + secrets.token_hex(16)
        log = folder / "debug.log"
        process, url = start_service(db, folder, log=log, level="debug", api_key=key)
        try:
            with httpx.Client(base_url=url, timeout=60, headers={"X-API-Key": key}) as keyed:
                status = keyed.get("/api/datasets").status_code
        finally:
            process.terminate()
            process.wait(timeout=60)
        text = log.read_text(errors="replace")
        leaked = key in text or key[-20:] in text
        return status, f"{'FAIL: the key is in the log' if leaked else 'ok: no key logged'}"

    return [
        ("deleted version, retrained (others)", once(deleted_version)),
        ("3 concurrent ONNX twin requests (others)", once(twin_requests)),
        ("alias set/delete from 4 threads (others)", alias_race),
        ("control: the model read from 4 threads (others)", reads_from_4_threads),
        ("debug log of a keyed request (others)", once(keys_in_log)),
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="short windows, smaller inputs")
    parser.add_argument("--seconds", type=float, help="of each window (default 8, quick 3)")
    parser.add_argument("--db", help="a store URL (default: SQLite in a temporary folder)")
    parser.add_argument(
        "--only",
        action="append",
        choices=["inputs", "pages", "sequences", "others"],
        help="these groups of cases only (repeatable; default all)",
    )
    parser.add_argument(
        "--split",
        action="store_true",
        help="predictions (the measuring client's, the cases') to a predictions-only process "
        "on the same store",
    )
    parser.add_argument(
        "--repeat", type=int, default=1, help="replay the cases this many times, in turn"
    )
    parser.add_argument(
        "--pace",
        type=float,
        help="replay each case at most once per this many seconds (default: back to back); "
        "two versions of the service then meet the same request rate",
    )
    args = parser.parse_args()
    seconds = args.seconds or (3.0 if args.quick else 8.0)
    rows = []
    with tempfile.TemporaryDirectory() as temporary:
        folder = Path(temporary)
        db = args.db or f"sqlite:///{folder / 'store.db'}"
        extract_takes(db, folder)
        process, url = start_service(db, folder, log=folder / "service.log")
        processes, prober_url, transport = [process], url, None
        if args.split:
            robots, prober_url = start_service(
                db, folder, log=folder / "robots.log", options=("--predictions-only",)
            )
            processes.append(robots)
            transport = ToPredictions(prober_url)
        pids = [p.pid for p in processes]
        try:
            with httpx.Client(base_url=url, timeout=600, transport=transport) as client:
                touch = upload(client, touch_arff(folder / "touch.arff", n=300, with_place=False))
                model = train(client, touch)
                train_named(client, "takes", "nb", "takes-nb")
                groups: dict[str, Callable[[], list[tuple[str, Callable[[], object]]]]] = {
                    "inputs": lambda: issue_cases(client, folder, args.quick),
                    "pages": lambda: run_pages(client, folder),
                    "sequences": lambda: [sequences_case(client, folder, args.quick)],
                    "others": lambda: others_cases(client, db, folder),
                }
                cases = [
                    case
                    for name, build in groups.items()
                    if not args.only or name in args.only
                    for case in build()
                ]
                cases *= args.repeat
                prober = Prober(prober_url, model)
                window(prober, pids, 1.0)  # warm: the model loaded
                idle_hwm = hwm_mb(pids)  # after every case's set-up
                for name, replay in cases:
                    replay = paced(replay, args.pace) if args.pace else replay
                    # the sides alternate, so that a change of the machine's load meets both
                    idle = window(prober, pids, seconds)
                    busy = window(prober, pids, seconds, replay)
                    rows.append((name, idle, busy, hwm_mb(pids)))
                prober.close()
        finally:
            for each in processes:
                each.terminate()
                each.wait(timeout=60)
    report(rows, idle_hwm)


def report(rows: list[tuple[str, Window, Window, float]], idle_hwm: float) -> None:
    header = ("case", "statuses", "RSS over idle", "VmHWM", "p99 idle", "p99 during", "ratio")
    table = [header]
    met = 0
    for name, idle, busy, hwm in rows:
        over = max(busy.peak_mb - idle.peak_mb, hwm - idle_hwm)
        p99_idle, p99_busy = percentile(idle.latencies, 99), percentile(busy.latencies, 99)
        ratio = p99_busy / p99_idle
        if not name.startswith(CONTROL):
            met += over < GOAL_MB and ratio <= GOAL_RATIO
        statuses = ",".join(str(s) for s in sorted(set(busy.statuses))) or "-"
        table.append(
            (
                name,
                f"{statuses} x{len(busy.statuses)}",
                f"{busy.peak_mb - idle.peak_mb:+.0f} MB",
                f"{hwm:.0f} MB ({hwm - idle_hwm:+.0f})",
                f"{p99_idle:.1f} ms",
                f"{p99_busy:.1f} ms",
                f"{ratio:.1f}x" + (" !" if ratio > GOAL_RATIO or over >= GOAL_MB else ""),
            )
        )
    widths = [max(len(row[i]) for row in table) for i in range(len(header))]
    for row in table:
        print("  ".join(cell.ljust(width) for cell, width in zip(row, widths, strict=True)))
    print(f"\nservice VmHWM once every case was set up: {idle_hwm:.0f} MB")
    cases = sum(not name.startswith(CONTROL) for name, *_ in rows)
    print(
        f"{met} of {cases} cases within {GOAL_MB} MB over idle and {GOAL_RATIO:g}x p99 "
        "(controls, the same load without the case's harm, not counted)"
    )
    for name, _, busy, _ in rows:
        if busy.verdict:
            print(f"{name}: {busy.verdict}")


if __name__ == "__main__":
    main()
