"""touchbench.Client against the raw httpx REST calls it makes, side by side, alternating.

    .venv/bin/python perf/client_overhead.py [--rounds 200] [--instances 1,100]

Starts ``touchbench serve`` on loopback with an API key (a SQLite store of its own), uploads
Mini (``../shared/datasets``; a synthetic data set of the same shape without it), runs a
small benchmark and trains its best classifier once, then times each verb both ways in
the same process, in alternating order round after round: the client (request built from
Python arguments, the answer validated into the service's response models, errors mapped)
and a plain ``httpx.Client`` sending the same request and decoding the JSON.  Both keep
their connection alive.  A second table replays the answers recorded from the service in
process (httpx's MockTransport), so that what is left is each side's own work, free of the
service's time and of the machine's load.  Prints medians, the ratio client / raw and the
overhead per call; nothing here is asserted.
"""

from __future__ import annotations

import argparse
import os
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import httpx

ROOT = Path(__file__).resolve().parents[1]
MINI = ROOT.parent / "shared" / "datasets" / "uc3m-touch" / "mini" / "gesture_and_place.arff"
sys.path.insert(0, str(ROOT))
KEY = "perf-client-overhead-key-0123456789"

from touchbench.app.python.client import Client  # noqa: E402 (after the path)


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def start_service(folder: Path) -> tuple[subprocess.Popen[bytes], str]:
    port = free_port()
    environment = {
        **os.environ,
        "TOUCHBENCH_API_KEY": KEY,
        "TOUCHBENCH_WORK_DIR": str(folder / "work"),
        "TOUCHBENCH_JOB_WORKERS": "1",
    }
    environment.pop("TOUCHBENCH_DATABASE_URL", None)
    log = (folder / "service.log").open("ab")
    process = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "touchbench.app.cli.main",
            "--db",
            f"sqlite:///{folder / 'touchbench.db'}",
            "serve",
            "--port",
            str(port),
            "--log-level",
            "warning",
        ],
        cwd=ROOT,
        env=environment,
        stdout=log,
        stderr=subprocess.STDOUT,
        start_new_session=True,
    )
    url = f"http://127.0.0.1:{port}"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        assert process.poll() is None, (folder / "service.log").read_text()[-2000:]
        try:
            if httpx.get(f"{url}/healthz", timeout=2).status_code == 200:
                return process, url
        except httpx.HTTPError:
            pass
        time.sleep(0.2)
    raise SystemExit("the service did not start")


def data_file(folder: Path) -> Path:
    if MINI.exists():
        return MINI
    from tests.support.synthetic import touch_arff

    return touch_arff(folder / "touch.arff", n=600)


def measure(pairs: Pairs, rounds: int) -> dict[str, tuple[list[float], list[float]]]:
    """Per verb, the seconds of each client call and each raw call, alternating which goes
    first from one round to the next."""
    times: dict[str, tuple[list[float], list[float]]] = {name: ([], []) for name in pairs}
    for client_call, raw_call in pairs.values():  # warm both: connections, caches
        for _ in range(3):
            client_call()
            raw_call()
    for i in range(rounds):
        for name, (client_call, raw_call) in pairs.items():
            order = [(0, client_call), (1, raw_call)]
            for side, call in order if i % 2 == 0 else order[::-1]:
                start = time.perf_counter()
                call()
                times[name][side].append(time.perf_counter() - start)
    return times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=200)
    parser.add_argument("--instances", default="1,100", help="Predictions per request.")
    args = parser.parse_args()

    with tempfile.TemporaryDirectory() as temporary:
        folder = Path(temporary)
        process, url = start_service(folder)
        try:
            run(url, data_file(folder), args.rounds, [int(n) for n in args.instances.split(",")])
        finally:
            process.terminate()
            process.wait(timeout=60)


class Recording(httpx.BaseTransport):
    """The real transport, keeping the last answer to each request for :class:`Replay`."""

    def __init__(self) -> None:
        self.real = httpx.HTTPTransport()
        self.answers: dict[tuple[str, str, bytes], tuple[int, bytes, str]] = {}

    def handle_request(self, request: httpx.Request) -> httpx.Response:
        response = self.real.handle_request(request)
        body = response.read()
        kind = response.headers.get("content-type", "application/json")
        self.answers[(request.method, request.url.path, request.url.query)] = (
            response.status_code,
            body,
            kind,
        )
        return httpx.Response(response.status_code, content=body, headers={"content-type": kind})


def replay(answers: dict[tuple[str, str, bytes], tuple[int, bytes, str]]) -> httpx.MockTransport:
    """Answers recorded from the service, given back in process: what remains is each
    side's own work (building the request, reading the upload, decoding, validating)."""

    def answer(request: httpx.Request) -> httpx.Response:
        request.read()  # the body is built and read, as a socket would
        status, body, kind = answers[(request.method, request.url.path, request.url.query)]
        return httpx.Response(status, content=body, headers={"content-type": kind})

    return httpx.MockTransport(answer)


Pairs = dict[str, tuple[Callable[[], Any], Callable[[], Any]]]


def verbs(
    client: Client, raw: httpx.Client, path: Path, run_id: int, model_id: int, rows: list[Any]
) -> Pairs:
    """Each verb through the client and as the raw request it makes."""

    def raw_upload() -> Any:
        with path.open("rb") as file:  # as the client sends it: the file read as it goes
            answer = raw.post(
                "/api/datasets", files={"file": (path.name, file)}, data={"name": "perf"}
            )
        return answer.raise_for_status().json()

    pairs: Pairs = {
        "run (GET /api/runs/{id})": (
            lambda: client.run(run_id),
            lambda: raw.get(f"/api/runs/{run_id}").raise_for_status().json(),
        ),
        "leaderboard": (
            lambda: client.leaderboard(run_id),
            lambda: raw.get(f"/api/runs/{run_id}/leaderboard").raise_for_status().json(),
        ),
        "leaderboard + folds": (
            lambda: client.leaderboard(run_id)._fold_scores,
            lambda: (
                raw.get(f"/api/runs/{run_id}/leaderboard").raise_for_status().json(),
                raw.get(f"/api/runs/{run_id}/folds", params={"metric": "f1_weighted"})
                .raise_for_status()
                .json(),
            ),
        ),
        "models": (
            lambda: client.models(),
            lambda: raw.get("/api/models", params={"limit": 1000}).raise_for_status().json(),
        ),
        "upload (already stored)": (lambda: client.upload(path, name="perf"), raw_upload),
    }
    for chosen in rows:
        body = {"instances": chosen, "missing": "allow"}
        pairs[f"predict {len(chosen)} instance(s)"] = (
            lambda chosen=chosen: client.predict(model_id, chosen, missing="allow"),  # type: ignore[misc]
            lambda body=body: (  # type: ignore[misc]
                raw.post(f"/api/models/{model_id}/predict", json=body).raise_for_status().json()
            ),
        )
    return pairs


def show(title: str, times: dict[str, tuple[list[float], list[float]]]) -> None:
    print(title)
    print(f"{'verb':32} {'client':>9} {'raw httpx':>10} {'ratio':>7} {'overhead':>9}")
    for name, (mine, theirs) in times.items():
        a, b = statistics.median(mine) * 1000, statistics.median(theirs) * 1000
        print(f"{name:32} {a:9.3f} {b:10.3f} {a / b:7.3f} {a - b:9.3f}")


def run(url: str, path: Path, rounds: int, sizes: list[int]) -> None:
    recording = Recording()
    client = Client(url, api_key=KEY, timeout=120, transport=recording)
    raw = httpx.Client(base_url=url, headers={"X-API-Key": KEY}, timeout=120, transport=recording)
    imported = client.upload(path, name="perf")
    bench = client.bench(
        "perf",
        target=imported.targets[0],
        classifiers=["nb", "zeror", "j48"],
        folds=3,
        wait=True,
        progress=False,
    )
    assert bench.status == "done", bench.schema.error
    model = client.train(run=bench, name="perf-best", wait=True, progress=False).model()
    described = client.dataset("perf")
    features = [a.name for a in described.attributes if a.name not in described.targets]
    # Mini's features are numeric; what the model predicts matters not here
    rows = [[dict.fromkeys(features, 0.5) for _ in range(n)] for n in sizes]

    live = measure(verbs(client, raw, path, bench.id, model.id, rows), rounds)
    show(f"over loopback: {rounds} rounds per verb, alternating; medians in ms; {path.name}", live)
    client.close()
    raw.close()

    answers = dict(recording.answers)
    client = Client(url, api_key=KEY, transport=replay(answers))
    raw = httpx.Client(base_url=url, headers={"X-API-Key": KEY}, transport=replay(answers))
    local = measure(verbs(client, raw, path, bench.id, model.id, rows), rounds)
    show("\nthe same answers replayed in process (each side's own work only); medians in ms", local)
    client.close()
    raw.close()


if __name__ == "__main__":
    main()
