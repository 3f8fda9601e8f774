"""The live view's delay: from a touch's end to its mark on the page.

Run from the repository root::

    .venv/bin/python perf/live_view.py [--rounds 2] [--touches 15] [--classifier cc:rf]

A model (``--classifier``) is trained on the ``uc3m-audio`` features of three simulated
3-microphone sessions (44.1 kHz); ``touchbench serve`` runs on loopback; then, alternating
round after round (the machine is shared, so that drift hits both alike):

* the page: headless Chromium (Debian's, through Playwright) opens ``/live`` on the model
  with the simulated sensor (``--touches`` touches, real time) and, for each touch, takes
  ``performance.timeOrigin + performance.now()`` in the animation frame that draws its
  mark, minus the touch's ``ended_at`` (the service's clock when the touch's last sample
  was read: the same clock on loopback);
* the socket alone: a Python client on the same source, its clock at each touch's message
  minus ``ended_at``: what the service and the transport take, without the page.

It prints p50/p90/p99/max of each, and of the service's own ``latency_ms`` (from the end of
the event to the prediction, as ``touchbench live`` reports it, any lag of the service
behind the source included); then, per touch, the delay less its ``latency_ms``: what the
transport and the page add to the prediction, the share that the machine's other load
touches least.  Goal: the page's p99 under 100 ms.

Not a test: nothing is asserted.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # the tests' helpers start the service
CHROMIUM = Path(os.environ.get("TOUCHBENCH_CHROMIUM", "/usr/bin/chromium"))


def percentiles(values: list[float]) -> str:
    p50, p90, p99 = np.percentile(values, [50, 90, 99])
    return f"{p50:8.1f} {p90:8.1f} {p99:8.1f} {max(values):8.1f} {len(values):6d}"


def train_model(folder: Path, database: str, classifier: str) -> str:
    from touchbench.app.schemas.extraction import ExtractRequest
    from touchbench.app.schemas.models import TrainRequest
    from touchbench.app.services.extraction import extract_and_store
    from touchbench.app.services.models import train
    from touchbench.app.services.simulation import write_contact_mic_sessions
    from touchbench.app.store.database import Store

    store = Store(database)
    try:
        recordings, labels = write_contact_mic_sessions(folder / "sessions", trials=3)
        extract_and_store(store, ExtractRequest(recordings=recordings, labels=labels, name="touch"))
        return train(store, TrainRequest(dataset="touch", classifier=classifier)).name
    finally:
        store.dispose()


def serve(folder: Path, database: str) -> tuple[subprocess.Popen[bytes], str]:
    import httpx

    from tests.support.service import free_port

    port = free_port()
    environment = {**os.environ, "TOUCHBENCH_WORK_DIR": str(folder / "work")}
    command = ["-m", "touchbench.app.cli.main", "--db", database, "serve", "--port", str(port)]
    process = subprocess.Popen(
        [sys.executable, *command, "--log-level", "warning"],
        cwd=ROOT,
        env=environment,
    )
    url = f"http://127.0.0.1:{port}"
    for _ in range(600):
        try:
            if httpx.get(f"{url}/healthz", timeout=2).status_code == 200:
                return process, url
        except httpx.HTTPError:
            pass
        time.sleep(0.2)
    process.kill()
    raise SystemExit("the service did not start")


def page_round(
    browser: object, url: str, model: str, touches: int, seed: int
) -> tuple[list[float], list[float]]:
    """Delays (ms) from each touch's end to its mark on the page, and from its prediction
    (the end plus the service's ``latency_ms``) to its mark."""
    context = browser.new_context(viewport={"width": 1280, "height": 720})  # type: ignore[attr-defined]
    page = context.new_page()
    page.goto(f"{url}/live?model={model}")
    page.get_by_label("Touches").fill(str(touches))
    page.get_by_label("Seed").fill(str(seed))
    page.get_by_role("button", name="Start").click()
    page.wait_for_selector("#live-touches[data-state=ended]", timeout=(touches * 3 + 60) * 1000)
    page.wait_for_timeout(100)  # the last touch's animation frame
    rows = page.locator("#live-touches tbody tr.touch").evaluate_all(
        "rows => rows.map(row => [Number(row.dataset.delayMs), Number(row.dataset.latencyMs)])"
    )
    context.close()
    return [float(delay) for delay, _ in rows], [float(delay - late) for delay, late in rows]


def socket_round(url: str, model: str, touches: int, seed: int) -> tuple[list[float], list[float]]:
    """Delays (ms) from each touch's end to its message in a Python client, and the
    service's own latencies."""
    from websockets.exceptions import ConnectionClosed
    from websockets.sync.client import connect

    delays, latencies, after = [], [], []
    address = url.replace("http://", "ws://") + f"/api/models/{model}/live"
    with connect(address, open_timeout=60) as socket:
        socket.send(json.dumps({"source": {"kind": "simulated", "touches": touches, "seed": seed}}))
        try:
            while True:
                message = json.loads(socket.recv(timeout=120))
                if "ended_at" in message:
                    delays.append(1000 * (time.time() - message["ended_at"]))
                    latencies.append(message["latency_ms"])
                    after.append(delays[-1] - latencies[-1])
        except ConnectionClosed:
            pass
    return delays, latencies, after


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--touches", type=int, default=15)
    parser.add_argument("--classifier", default="cc:rf")
    args = parser.parse_args()

    from playwright.sync_api import sync_playwright

    with tempfile.TemporaryDirectory() as temporary:
        folder = Path(temporary)
        database = f"sqlite:///{folder / 'touchbench.db'}"
        model = train_model(folder, database, args.classifier)
        process, url = serve(folder, database)
        page: list[float] = []
        page_share: list[float] = []
        alone: list[float] = []
        alone_share: list[float] = []
        service: list[float] = []
        try:
            with sync_playwright() as playwright:
                browser = playwright.chromium.launch(executable_path=str(CHROMIUM), headless=True)
                socket_round(url, model, 1, 0)  # the service's first session pays its imports
                for round_ in range(args.rounds):
                    seed = 100 + round_
                    delays, shares = page_round(browser, url, model, args.touches, seed)
                    page += delays
                    page_share += shares
                    delays, latencies, shares = socket_round(url, model, args.touches, seed)
                    alone += delays
                    service += latencies
                    alone_share += shares
                browser.close()
        finally:
            process.terminate()
            process.wait(timeout=30)
    print(
        f"Live view, {model} on the simulated sensor ({args.touches} touches x {args.rounds} "
        "rounds, real time, loopback), ms from a touch's end"
    )
    print(f"{'':<44} {'p50':>8} {'p90':>8} {'p99':>8} {'max':>8} {'n':>6}")
    print(f"{'to its mark on the page (Chromium)':<44} {percentiles(page)}")
    print(f"{'to its message in a Python client':<44} {percentiles(alone)}")
    print(f"{'to its prediction (the service, latency_ms)':<44} {percentiles(service)}")
    print("ms from a touch's prediction (its end + latency_ms)")
    print(f"{'to its mark on the page (Chromium)':<44} {percentiles(page_share)}")
    print(f"{'to its message in a Python client':<44} {percentiles(alone_share)}")


if __name__ == "__main__":
    main()
