"""The web page's answers as a client reads them, on a real service over SQLite:
frames without data, fragments escaped and behind the same errors as the API,
the strict Content-Security-Policy and nothing the page would be refused under it, plots of
every kind of run with their labels, figures drawn by threads at once."""

from __future__ import annotations

import re
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from urllib.parse import quote

import pytest

from tests.support.browser import figure_texts
from tests.support.cli_runner import run_cli
from tests.support.figures import FETCHES
from tests.support.service import Server, finished
from tests.support.synthetic import touch_arff
from touchbench.app.web.rendering import CONTENT_SECURITY_POLICY

MARKUP_NAME = "<i>mark<i>"  # markup, without the slash a name may not hold
MARKUP_ATTRIBUTE = "<img src=x onerror=alert(1)>"
DATA_URI = re.compile(r'src="(data:image/svg\+xml;base64,[^"]+)"')


def _markup_arff(path: Path) -> Path:
    lines = [
        "@relation markup",
        f"@attribute '{MARKUP_ATTRIBUTE}' numeric",
        "@attribute f1 numeric",
        "@attribute class {'<b>bold</b>', plain}",
        "@data",
    ]
    labels = ("'<b>bold</b>'", "plain")
    lines += [f"{i % 7},{i % 3},{labels[i % 2]}" for i in range(30)]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def _bench(capsys: pytest.CaptureFixture[str], db: str, *args: str) -> int:
    result = run_cli(capsys, db, "bench", *args, "--json")
    assert result.code == 0, result.err
    return int(result.json()["run_id"])


def _figures(html: str) -> list[list[str]]:
    return [figure_texts(uri) for uri in DATA_URI.findall(html)]


def test_frames_fragments_escaping_errors_and_policy(
    capsys: pytest.CaptureFixture[str], sqlite_server: Server, tmp_path: Path
) -> None:
    db, api = sqlite_server.database_url, sqlite_server.client
    path = _markup_arff(tmp_path / "markup.arff")
    assert run_cli(capsys, db, "import", str(path), "--name", MARKUP_NAME).code == 0
    ref = api.get("/api/datasets").json()["datasets"][0]["id"]

    # every answer of the page carries the policy; frames hold no data
    for url in ("/", f"/datasets/{ref}", "/runs/new", "/runs/1", "/compare", "/models/x"):
        frame = api.get(url)
        assert frame.status_code == 200, url
        assert frame.headers["content-security-policy"] == CONTENT_SECURITY_POLICY
        assert frame.headers["content-type"].startswith("text/html")
        assert "<i>" not in frame.text and "bold" not in frame.text
    listing = api.get("/fragments/datasets")
    assert listing.headers["content-security-policy"] == CONTENT_SECURITY_POLICY

    # what the store holds is escaped wherever it shows
    assert "&lt;i&gt;mark&lt;i&gt;" in listing.text and MARKUP_NAME not in listing.text
    described = api.get(f"/fragments/datasets/{ref}")
    assert described.status_code == 200, described.text
    assert "&lt;img src=x onerror=alert(1)&gt;" in described.text
    assert MARKUP_ATTRIBUTE not in described.text and "<b>bold" not in described.text
    classes = _figures(described.text)
    assert classes and "class (30 instances)" in classes[0]
    assert {"<b>bold</b>", "plain"} <= set(classes[0])  # the SVG's text, unescaped by XML

    # nothing the policy would refuse: no inline script or style, nothing from elsewhere
    static = [api.get("/static/touchbench.js"), api.get("/static/touchbench.css")]
    assert all(answer.status_code == 200 for answer in static)
    for text in (api.get("/").text, described.text, *(answer.text for answer in static)):
        assert not FETCHES.search(text)
        assert not re.search(r"\sstyle\s*=|<style|\son\w+\s*=\s*['\"]", text)
        assert all(" src=" in tag for tag in re.findall(r"<script[^>]*>", text))

    # unknown things: the API's JSON errors
    for url, status in (
        ("/fragments/runs/99999/progress", 404),
        ("/fragments/runs/99999/leaderboard", 404),
        ("/fragments/datasets/nothing", 404),
        ("/fragments/models/nothing", 404),
        ("/fragments/runs/abc/progress", 422),
    ):
        answer = api.get(url)
        assert answer.status_code == status, (url, answer.text)
        assert answer.json()["error"]["message"]


def test_plots_of_every_kind_of_run_and_figures_drawn_at_once(
    capsys: pytest.CaptureFixture[str], sqlite_server: Server, tmp_path: Path
) -> None:
    db, api = sqlite_server.database_url, sqlite_server.client
    data = touch_arff(tmp_path / "t.arff", n=60)
    assert run_cli(capsys, db, "import", str(data), "--name", "touch").code == 0
    single = _bench(capsys, db, "touch", "--target", "gesture", "-c", "nb,zeror,j48", "-k", "3")
    multi = _bench(capsys, db, "touch", "-c", "cr:nb,cc:j48", "-k", "3")

    # the progress box's buttons follow the run's status: a done run trains its best
    # classifier, a stopped one is resumed
    done = api.get(f"/fragments/runs/{single}/progress").text
    assert "Train its best classifier" in done and "Resume" not in done and "Cancel" not in done
    queued = api.post(
        "/api/runs",
        json={"dataset": "touch", "target": "gesture", "classifiers": ["nb"], "folds": 3},
    )
    assert queued.status_code == 202, queued.text
    stopped = queued.json()["id"]
    assert api.post(f"/api/runs/{stopped}/cancel").status_code == 200
    assert sqlite_server.wait_for(f"/api/runs/{stopped}", finished)["status"] == "cancelled"
    resumable = api.get(f"/fragments/runs/{stopped}/progress").text
    assert "Resume" in resumable and "Train its best classifier" not in resumable

    single_plots = _figures(api.get(f"/fragments/runs/{single}/plots").text)
    assert "f1_weighted per fold (higher is better; bar: mean)" in single_plots[0]
    assert "gesture (60 instances)" in single_plots[1]

    board = api.get(f"/fragments/runs/{multi}/leaderboard").text
    assert 'data-metric="hamming_score"' in board
    assert board.index('data-classifier="cr:nb"') > 0 and 'data-classifier="cc:j48"' in board
    multi_plots = _figures(api.get(f"/fragments/runs/{multi}/plots").text)
    per_target = next(texts for texts in multi_plots if "accuracy" in " ".join(texts))
    assert {"gesture", "place", "cr:nb", "cc:j48"} <= set(per_target)
    classifier = api.get(f"/fragments/runs/{multi}/classifiers/{quote('cc:j48', safe='')}")
    assert classifier.status_code == 200, classifier.text
    confusion = _figures(classifier.text)[0]
    assert {"gesture", "place", "head", "arm", "tap", "predicted"} <= set(confusion)

    compared = api.get("/fragments/compare", params={"runs": [single], "metric": "nope"})
    assert compared.status_code == 200 and "no &#39;nope&#39; scores" in compared.text
    folds = api.get("/fragments/compare", params={"runs": [single]}).text
    diagram = _figures(folds)[0]
    assert any(text.startswith("CD = ") for text in diagram)
    assert "3 folds as blocks" in " ".join(diagram)
    missing = api.get(f"/fragments/runs/{single}/classifiers/rf")
    assert missing.status_code == 404 and "no classifier 'rf'" in missing.json()["error"]["message"]

    # matplotlib's settings are global: threads drawing at once must keep text as text
    urls = [f"/fragments/runs/{single}/classifiers/{name}" for name in ("nb", "j48", "zeror")] * 3
    with ThreadPoolExecutor(len(urls)) as pool:
        pages = list(pool.map(lambda url: api.get(url), urls))
    for page in pages:
        assert page.status_code == 200
        assert "predicted" in _figures(page.text)[0]
