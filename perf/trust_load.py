"""Bounded work per request (issue 21): the service's peak memory while a recordings upload
declaring 20,000 targets is refused, the time to refuse 50,000 JSON prediction instances,
and the one-instance prediction latency while another client asks for the heaviest page
(the data set fragment of the widest data set the default limits accept), side by side
with the same latency on an idle service.

    .venv/bin/python perf/trust_load.py [--predictions 300] [--targets 1000] [--rounds 3]

Prints a table of figures and ratios; nothing here is asserted.  The issue measured,
before: the fragment of a 50/200/800-target data set 2.6 s / 27.5 s / no answer in 120 s,
the service at 9.2 GB for the 20,000-target upload's data set, a one-instance prediction
up to 7 s meanwhile, and 6.4 s to refuse 50,000 instances.
"""

from __future__ import annotations

import argparse
import json
import os
import re
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
sys.path.insert(0, str(ROOT))

from perf.serve import free_port, percentile, wait_until_up  # noqa: E402 (after the path is set)
from tests.support.synthetic import touch_arff  # noqa: E402


def start_service(db: str, folder: Path) -> tuple[subprocess.Popen[bytes], str]:
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
    ]
    process = subprocess.Popen(
        [*command, "--log-level", "warning"], cwd=ROOT, env=environment, start_new_session=True
    )
    return process, wait_until_up(port)


def peak_rss_mb(pid: int) -> float:
    """``VmHWM`` of a process, in MB."""
    status = Path(f"/proc/{pid}/status").read_text()
    found = re.search(r"^VmHWM:\s+(\d+) kB", status, re.MULTILINE)
    assert found, status
    return int(found.group(1)) / 1024


def wide_arff(path: Path, n_targets: int) -> Path:
    """A data set of ``n_targets`` binary targets and 5 features, 60 instances."""
    rng = np.random.default_rng(0)
    lines = [f"@relation 'wide: -C {n_targets}'"]
    lines += [f"@attribute y{i} {{0,1}}" for i in range(n_targets)]
    lines += [f"@attribute f{i} numeric" for i in range(5)] + ["@data"]
    for _ in range(60):
        labels = rng.integers(0, 2, n_targets).astype(str).tolist()
        lines.append(",".join(labels + [f"{v:.3f}" for v in rng.random(5)]))
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def upload(client: httpx.Client, path: Path) -> int:
    with path.open("rb") as handle:
        response = client.post("/api/datasets", files={"file": (path.name, handle)})
    assert response.is_success, response.text
    return int(response.json()["id"])


def train(client: httpx.Client, dataset: int) -> int:
    job = client.post("/api/models", json={"dataset": dataset, "classifier": "nb"}).json()["job"]
    while True:
        body = client.get(f"/api/jobs/{job}").json()
        if body["status"] not in ("queued", "running"):
            assert body["status"] == "done", body
            return int(body["result"]["model_id"])
        time.sleep(0.2)


def refuse_wide_labels(client: httpx.Client) -> tuple[int, float]:
    """The issue's recordings upload: a labels CSV of 20,000 target columns (status, s)."""
    import soundfile  # the one part of the script that writes audio

    header = "file," + ",".join(f"t{i}" for i in range(20_000))
    labels = (header + "\ns1.wav," + ",".join(["1"] * 20_000) + "\n").encode()
    with tempfile.NamedTemporaryFile(suffix=".wav") as wav:
        soundfile.write(wav.name, np.zeros(4410, dtype=np.float32), 44100)
        files = [
            ("recordings", ("s1.wav", Path(wav.name).read_bytes())),
            ("labels", ("session.csv", labels)),
        ]
        start = time.perf_counter()
        response = client.post("/api/datasets/recordings", files=files)
    return response.status_code, time.perf_counter() - start


def refuse_many_instances(client: httpx.Client, record: dict[str, object]) -> tuple[int, float]:
    body = json.dumps({"instances": [record] * 50_000})
    start = time.perf_counter()
    response = client.post(
        "/api/models/1/predict", content=body, headers={"Content-Type": "application/json"}
    )
    return response.status_code, time.perf_counter() - start


def latencies(url: str, model: int, record: dict[str, object], n: int) -> list[float]:
    times = []
    with httpx.Client(base_url=url, timeout=120) as client:
        for _ in range(10):  # warm-up: the model in the cache, the connection open
            client.post(f"/api/models/{model}/predict", json={"instances": [record]})
        for _ in range(n):
            start = time.perf_counter()
            response = client.post(f"/api/models/{model}/predict", json={"instances": [record]})
            times.append(time.perf_counter() - start)
            assert response.status_code == 200, response.text
    return times


def under_load(
    url: str, model: int, record: dict[str, object], n: int, page: str
) -> tuple[list[float], list[float]]:
    """Prediction latencies while another client asks for ``page`` again and again, and
    the page's own times."""
    stop = threading.Event()
    pages: list[float] = []

    def heavy() -> None:
        with httpx.Client(base_url=url, timeout=300) as client:
            while not stop.is_set():
                start = time.perf_counter()
                assert client.get(page).status_code == 200
                pages.append(time.perf_counter() - start)

    thread = threading.Thread(target=heavy, daemon=True)
    thread.start()
    try:
        times = latencies(url, model, record, n)
    finally:
        stop.set()
        thread.join()
    return times, pages


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--predictions", type=int, default=300)
    parser.add_argument("--targets", type=int, default=1000, help="of the widest data set")
    parser.add_argument("--rounds", type=int, default=3, help="idle and loaded, alternating")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as temporary:
        folder = Path(temporary)
        process, url = start_service(f"sqlite:///{folder / 'store.db'}", folder)
        try:
            with httpx.Client(base_url=url, timeout=300) as client:
                touch = upload(client, touch_arff(folder / "touch.arff", n=300, with_place=False))
                wide = upload(client, wide_arff(folder / "wide.arff", args.targets))
                model = train(client, touch)
                page = f"/fragments/datasets/{wide}"
                client.get(page)  # the first draw imports matplotlib
                before = peak_rss_mb(process.pid)
                status, refused_in = refuse_wide_labels(client)
                after = peak_rss_mb(process.pid)
                record = {"f0": 0.1, "f1": 0.2, "f2": -0.3, "f3": 1.0, "mic": "left"}
                many_status, many_in = refuse_many_instances(client, record)
            # the sides alternate, so that a change of the machine's load meets both
            idle: list[float] = []
            loaded: list[float] = []
            pages: list[float] = []
            share = max(1, args.predictions // args.rounds)
            for _ in range(args.rounds):
                idle += latencies(url, model, record, share)
                times, drawn = under_load(url, model, record, share, page)
                loaded += times
                pages += drawn
            peak = peak_rss_mb(process.pid)  # the fragments drawn again and again included
        finally:
            process.terminate()
            process.wait(timeout=60)
    p99_idle, p99_loaded = percentile(idle, 99), percentile(loaded, 99)
    p50_idle, p50_loaded = percentile(idle, 50), percentile(loaded, 50)
    rows = [
        ("20,000-target recordings upload", f"HTTP {status} in {refused_in:.2f} s"),
        ("service peak RSS before / after it", f"{before:.0f} MB / {after:.0f} MB"),
        ("50,000 JSON instances", f"HTTP {many_status} in {many_in:.2f} s"),
        (
            f"data set fragment, {args.targets} targets",
            f"median {statistics.median(pages):.2f} s over {len(pages)} (max {max(pages):.2f})",
        ),
        ("service peak RSS at the end", f"{peak:.0f} MB"),
        ("1-instance prediction, idle", f"p50 {p50_idle:.1f} ms  p99 {p99_idle:.1f} ms"),
        ("... while the fragment is asked", f"p50 {p50_loaded:.1f} ms  p99 {p99_loaded:.1f} ms"),
        ("p99 loaded / idle", f"{p99_loaded / p99_idle:.1f}x (p50 {p50_loaded / p50_idle:.1f}x)"),
    ]
    width = max(len(name) for name, _ in rows)
    for name, value in rows:
        print(f"{name:<{width}}  {value}")


if __name__ == "__main__":
    main()
