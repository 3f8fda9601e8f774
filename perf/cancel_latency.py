"""How long a cancel takes to reach a running run, over HTTP.

    .venv/bin/python perf/cancel_latency.py [--cancels 20] [--workers 1]

Starts a real ``touchbench serve`` on loopback with a SQLite store (``--db`` for another,
e.g. a PostgreSQL URL), imports a synthetic data set, and ``--cancels`` times: submits a run
(``mlp,rf`` x 10 folds x 10 repeats, far longer than the measure), waits until its first
task is stored, asks ``POST /api/runs/{id}/cancel`` and polls ``GET /api/runs/{id}`` every
10 ms until the run says ``cancelled``.  The latency is the time from sending the cancel to
the first answer that says so: what a client waiting on the run sees.  Prints every figure,
the median and the maximum; nothing is asserted.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

import httpx

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from perf.serve import start_service  # noqa: E402 (after the path is set)

POLL = 0.01
FINAL = ("cancelled", "done", "failed", "interrupted")


def wait_until(client: httpx.Client, path: str, done: object, timeout: float = 300.0) -> dict:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        body = client.get(path).json()
        if done(body):  # type: ignore[operator]
            return body
        time.sleep(POLL)
    raise SystemExit(f"{path}: not there after {timeout:g} s")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cancels", type=int, default=20)
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--db", default=None, help="store URL (default: a temporary SQLite)")
    args = parser.parse_args()

    from tests.support.synthetic import touch_arff

    folder = Path(tempfile.mkdtemp(prefix="touchbench-cancel-perf-"))
    db = args.db or f"sqlite:///{folder / 'touchbench.db'}"
    data = touch_arff(folder / "touch.arff", n=300)
    service, url = start_service(db, folder, args.workers)
    latencies: list[float] = []
    try:
        with httpx.Client(base_url=url, timeout=60) as client:
            with data.open("rb") as file:
                uploaded = client.post("/api/datasets", files={"file": file}, data={"name": "t"})
            uploaded.raise_for_status()
            request = {
                "dataset": "t",
                "target": "gesture",
                "classifiers": ["mlp", "rf"],
                "folds": 10,
                "repeats": 10,
            }
            for attempt in range(1, args.cancels + 1):
                started = client.post("/api/runs", json=request)
                started.raise_for_status()
                path = f"/api/runs/{started.json()['id']}"
                wait_until(client, path, lambda body: body["tasks_done"] >= 1)
                sent = time.perf_counter()
                client.post(f"{path}/cancel").raise_for_status()
                run = wait_until(client, path, lambda body: body["status"] in FINAL)
                latency = time.perf_counter() - sent
                latencies.append(latency)
                print(
                    f"cancel {attempt:2d}: {latency * 1000:7.0f} ms -> {run['status']} "
                    f"({run['tasks_done']} tasks kept)",
                    flush=True,
                )
    finally:
        service.terminate()
        service.wait(timeout=60)
    print(
        f"\ncancel latency over HTTP, {len(latencies)} cancels: "
        f"p50 {statistics.median(latencies) * 1000:.0f} ms, "
        f"max {max(latencies) * 1000:.0f} ms"
    )


if __name__ == "__main__":
    main()
