"""The run form and a run's answers in a real headless Chromium against a real service:
every field of the run request in its group with the request's defaults, bad values refused
by the page and then by the service under the request's field names, a raced run on a
total budget started from the form with the dropped classifier marked, calibration on the
run's page, the leaderboard with its CSV and calibration scored per recording when asked,
and an ablation started from the run's page with its plot; a page on another origin can
start none of these on the same (keyless) service."""

from __future__ import annotations

import csv
import io
import re
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from playwright.sync_api import Response, expect

from tests.support.browser import Tab, figure_texts, screen, static_site
from tests.support.recordings import PER_RECORDING, recorded_windows, store_dataset
from tests.support.service import Server, finished, servers
from tests.support.synthetic import touch_arff
from touchbench.app.schemas.runs import BenchRequest
from touchbench.app.web.routes.runs import RUN_GROUPS

#: A run or a job takes seconds; the first one also pays for the worker's imports.
TIMEOUT = 180_000
RESCORED = "re-scored per recording from the run's stored test-fold predictions"


def channels_arff(path: Path, *, n: int = 60, seed: int = 0) -> Path:
    """Gesture from two microphones' statistics (``_1``, ``_2``): the first hears it, the
    second is noise, so an ablation finds channel 1 needed and channel 2 can go."""
    rng = np.random.default_rng(seed)
    gestures = ["tap", "slap", "stroke"]
    lines = ["@relation 'channels: -C 1'", "@attribute gesture {tap, slap, stroke}"]
    lines += [f"@attribute {stat}_{mic} numeric" for mic in (1, 2) for stat in ("rms", "peak")]
    lines.append("@data")
    for i in range(n):
        g = i % 3
        heard = rng.normal(size=2) * 0.5 + 2.0 * g
        noise = rng.normal(size=2)
        lines.append(",".join([gestures[g], *(f"{v:.4f}" for v in (*heard, *noise))]))
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def service(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    """One service for the module, with two tiny data sets."""
    folder = tmp_path_factory.mktemp("runs")
    builds = servers(f"sqlite:///{folder / 'touchbench.db'}", folder)
    server = next(builds)()
    for data, name in (
        (touch_arff(folder / "touch.arff", n=150), "touch"),
        (channels_arff(folder / "channels.arff"), "channels"),
    ):
        with data.open("rb") as handle:
            answer = server.client.post(
                "/api/datasets", files={"file": (data.name, handle)}, data={"name": name}
            )
        assert answer.status_code == 201, answer.text
    yield server
    next(builds, None)


def test_a_raced_budgeted_run_from_the_form_marks_what_it_dropped(
    projector_tab: Tab, service: Server
) -> None:
    tab, page, api = projector_tab, projector_tab.page, service.client
    page.goto(f"{service.url}/runs/new?dataset=touch")
    form = page.locator("form[data-action=start-run]")
    expect(form).to_be_visible()

    # every field of the request, in its group, with the request's own defaults
    legends = form.locator("fieldset.group > legend")
    expect(legends).to_have_text([title for title, _ in RUN_GROUPS])
    for title, names in RUN_GROUPS:
        group = form.locator(f"fieldset[data-group='{title}']")
        for name in names:
            expect(group.locator(f"[data-field='{name}']")).to_have_count(1)
    assert set(BenchRequest.model_fields) == {
        name for name in form.locator("[data-field]").evaluate_all(
            "inputs => inputs.map(i => i.dataset.field)"
        )
    }  # fmt: skip
    expect(form.get_by_label("folds")).to_have_value("10")
    expect(form.get_by_label("race alpha")).to_have_value("0.01")
    expect(form.get_by_label("timeout")).to_have_value("600")
    help_id = form.get_by_label("budget total").get_attribute("aria-describedby")
    expect(page.locator(f"#{help_id}")).to_contain_text("Wall minutes for the whole run")

    # the page refuses a bound of the request before sending it
    form.get_by_label("race alpha").fill("0.7")
    form.get_by_role("button", name="Start the run").click()
    expect(form.locator(".outcome")).to_have_text("race_alpha: Input should be less than 0.5")
    expect(form.get_by_label("race alpha")).to_have_attribute("aria-invalid", "true")
    form.get_by_label("race alpha").fill("0.01")
    # the service refuses a rule across fields, naming its field
    form.get_by_label("race", exact=True).check()
    form.get_by_label("folds").fill("2")
    form.get_by_role("button", name="Start the run").click()
    expect(form.locator(".outcome")).to_contain_text("race: needs at least 3 folds")
    expect(form.locator(".outcome")).to_contain_text("(body.race)")
    expect(form.get_by_label("race", exact=True)).to_have_attribute("aria-invalid", "true")
    assert api.get("/api/runs").json()["runs"] == []

    form.locator("select[name=target]").select_option("gesture")
    form.get_by_label("classifiers").fill("zeror, nb, j48")
    form.get_by_label("folds").fill("5")
    form.get_by_label("seed").fill("3")
    form.get_by_label("budget total").fill("60")
    page.evaluate("window.scrollTo(0, 0)")
    screen(tab, "run-form")
    form.get_by_role("button", name="Start the run").click()
    page.wait_for_url(re.compile(r"/runs/\d+$"))
    run_id = int(page.url.rsplit("/", 1)[1])
    run = api.get(f"/api/runs/{run_id}").json()
    assert run["config"]["race"] == {"alpha": 0.01}, run["config"]
    assert (run["config"]["folds"], run["config"]["seed"], run["targets"]) == (5, 3, ["gesture"])

    # the run: zeror dropped after fold 3, marked in the leaderboard and said under it
    expect(page.locator("#run-status")).to_have_text("done", timeout=TIMEOUT)
    board = api.get(f"/api/runs/{run_id}/leaderboard").json()
    assert board["budget"]["minutes"] == 60
    zeror = next(row for row in board["leaderboard"] if row["classifier"] == "zeror")
    assert zeror["dropped"]["reason"] == "race" and zeror["dropped"]["after_fold"] == 3
    row = page.locator("#leaderboard-table tr[data-classifier='zeror']")
    expect(row).to_have_class("dropped")
    expect(row).to_contain_text("dropped after fold 3")
    expect(page.locator("#leaderboard")).to_contain_text("raced at alpha 0.01")
    expect(page.locator("#leaderboard")).to_contain_text(board["budget"]["note"])
    for other in ("nb", "j48"):
        expect(page.locator(f"#leaderboard-table tr[data-classifier='{other}']")).not_to_have_class(
            "dropped"
        )

    # calibration for every run: each classifier's ECE, and the reliability diagram
    calibration = page.locator("#calibration table[data-table='calibration']")
    for name in ("nb", "j48", "zeror"):
        expect(calibration.locator("tbody tr", has_text=name)).to_have_count(1)
    expect(page.locator("#calibration figure img")).to_be_visible()
    page.locator("#leaderboard").scroll_into_view_if_needed()
    screen(tab, "run-raced")


def test_an_ablation_started_from_the_run_page_shows_its_plot(
    projector_tab: Tab, service: Server
) -> None:
    tab, page, api = projector_tab, projector_tab.page, service.client
    created = api.post(
        "/api/runs", json={"dataset": "channels", "classifiers": ["nb"], "folds": 3}
    ).json()
    assert service.wait_for(f"/api/runs/{created['id']}", finished)["status"] == "done"
    page.goto(f"{service.url}/runs/{created['id']}")
    form = page.locator("form[data-url='/api/jobs/ablation']")
    expect(form.get_by_label("grouping")).to_have_value("channel")  # the request's default
    form.get_by_role("button", name="Start the ablation").click()
    expect(form.locator(".outcome")).to_contain_text("Job")
    job = page.locator("#ablation-job .job-box")
    expect(job.locator(".status")).to_have_text("done", timeout=TIMEOUT)
    image = job.locator("figure img")
    expect(image).to_be_visible()
    texts = figure_texts(image.get_attribute("src"))
    assert {"nb: channel 1", "nb: channel 2"} <= set(texts), texts
    result = api.get("/api/jobs").json()["jobs"][-1]["result"]
    verdicts = {entry["group"]: entry["verdict"] for entry in result["entries"]}
    assert verdicts["channel 1"] == "needed", verdicts
    table = job.locator("table[data-table='ablation']")
    expect(table.locator("tbody tr", has_text="channel 1")).to_contain_text("needed")
    job.scroll_into_view_if_needed()
    screen(tab, "run-ablation")


#: A page on another site: what a browser sends without asking (no-cors requests) to start
#: a run, an ablation, an extraction and a promotion on the service.
ATTACK = """<!doctype html>
<html><head><meta charset="utf-8"><title>another site</title></head><body><script>
async function attack(service, run) {
  const json = (body) => ({method: "POST", mode: "no-cors", body: JSON.stringify(body),
                           headers: {"Content-Type": "text/plain"}});
  const session = new FormData();
  session.append("recordings", new Blob(["RIFF"]), "take.wav");
  const tries = [
    ["/api/runs", json({dataset: "touch", classifiers: ["nb"], folds: 3})],
    ["/api/jobs/ablation", json({run: run})],
    ["/api/datasets/recordings", {method: "POST", mode: "no-cors", body: session}],
    ["/api/models/1/promote", {method: "POST", mode: "no-cors"}],
  ];
  const outcome = {};
  for (const [path, options] of tries) {
    try { await fetch(service + path, options); outcome[path] = "sent"; }
    catch (error) { outcome[path] = String(error); }
  }
  return outcome;
}
</script></body></html>
"""


@pytest.fixture
def foreign_site(tmp_path: Path) -> Iterator[str]:
    """A second web server on loopback (another port: another origin) serving the page."""
    (tmp_path / "attack.html").write_text(ATTACK)
    with static_site(tmp_path) as url:
        yield url


@pytest.fixture(scope="module")
def channels_run(service: Server) -> int:
    """A finished run on ``channels`` (data without recordings), made once for the tests
    that only read it: one needs a run to attack, another a run without recordings."""
    return _finished_run(service, "channels", 3)


def test_a_page_on_another_origin_can_start_nothing(
    tab: Tab, service: Server, foreign_site: str, channels_run: int
) -> None:
    api = service.client
    run_id = channels_run
    before = (api.get("/api/runs").json(), api.get("/api/jobs").json())
    statuses: dict[str, int] = {}

    def seen(response: Response) -> None:
        if response.url.startswith(service.url) and response.request.method == "POST":
            statuses[response.url.removeprefix(service.url)] = response.status

    tab.page.on("response", seen)
    tab.page.goto(f"{foreign_site}/attack.html")
    outcome = tab.page.evaluate("([s, r]) => attack(s, r)", [service.url, run_id])
    paths = ["/api/runs", "/api/jobs/ablation", "/api/datasets/recordings", "/api/models/1/promote"]
    assert outcome == dict.fromkeys(paths, "sent")
    assert statuses == dict.fromkeys(paths, 403)
    assert (api.get("/api/runs").json(), api.get("/api/jobs").json()) == before


def _finished_run(service: Server, dataset: str, folds: int) -> int:
    created = service.client.post(
        "/api/runs",
        json={"dataset": dataset, "classifiers": ["nb", "ridge"], "folds": folds, "seed": 3},
    )
    assert created.status_code == 202, created.text
    run_id = int(created.json()["id"])
    assert service.wait_for(f"/api/runs/{run_id}", finished)["status"] == "done"
    return run_id


def test_the_run_page_scores_per_recording_where_the_run_has_recordings(
    projector_tab: Tab, service: Server, channels_run: int
) -> None:
    tab, page, api = projector_tab, projector_tab.page, service.client
    store_dataset(service.database_url, recorded_windows(), "takes")
    store_dataset(service.database_url, recorded_windows(mixed=True), "mixed")
    takes, mixed = _finished_run(service, "takes", 4), _finished_run(service, "mixed", 4)
    plain = channels_run

    # a run on data without recordings: no choice offered
    page.goto(f"{service.url}/runs/{plain}")
    expect(page.locator("#leaderboard-table")).to_be_visible()
    expect(page.locator("select[name=aggregate]")).to_have_count(0)

    # a run on recorded windows: per window as it scored, per recording when asked
    page.goto(f"{service.url}/runs/{takes}")
    picker = page.locator("select[name=aggregate]")
    expect(picker).to_have_value("window")
    expect(page.locator("#leaderboard")).not_to_contain_text(PER_RECORDING)
    csv_link = page.locator("#progress a[data-download]")
    expect(csv_link).to_have_attribute("href", f"/api/runs/{takes}/leaderboard?format=csv")
    # nb's calibration (the cells: classifier, ECE, instances, folds, note) counts windows
    nb_calibration = page.locator("#calibration table[data-table='calibration'] tbody tr").filter(
        has=page.locator("td:first-child", has_text=re.compile(r"^nb$"))
    )
    expect(nb_calibration.locator("td").nth(2)).to_have_text("256")
    picker.select_option("recording")
    page.wait_for_url(re.compile(r"aggregate=recording"))
    expect(page.locator("#leaderboard")).to_contain_text(RESCORED)
    expect(page.locator("#leaderboard")).to_contain_text(PER_RECORDING)
    expect(page.locator("select[name=aggregate]")).to_have_value("recording")
    board = api.get(f"/api/runs/{takes}/leaderboard", params={"aggregate": "recording"}).json()
    for row in board["leaderboard"]:
        mean = row["metrics"]["f1_weighted"]["mean"]
        cells = page.locator(f"#leaderboard-table tr[data-classifier='{row['classifier']}'] td")
        expect(cells.nth(3)).to_contain_text(f"{mean:.4f}")
    # the CSV and the calibration follow the choice: 16 recordings, the ECE the API says
    classes = api.get(f"/api/runs/{takes}/classes", params={"aggregate": "recording"}).json()
    nb = next(c for c in classes["classifiers"] if c["classifier"] == "nb")["calibration"]
    expect(nb_calibration.locator("td").nth(2)).to_have_text("16")
    expect(nb_calibration.locator("td").nth(1)).to_have_text(f"{nb['ece']:.4f}")
    expect(csv_link).to_have_attribute(  # the picker sent the page's metric with its choice
        "href", f"/api/runs/{takes}/leaderboard?format=csv&metric=f1_weighted&aggregate=recording"
    )
    with page.expect_download() as downloading:
        csv_link.click()
    rows = list(csv.DictReader(io.StringIO(downloading.value.path().read_text(encoding="utf-8"))))
    assert [row["classifier"] for row in rows] == [
        row["classifier"] for row in board["leaderboard"]
    ]
    assert {row["aggregate"] for row in rows} == {"recording"}
    for row, ranked in zip(rows, board["leaderboard"], strict=True):
        assert float(row["f1_weighted_mean"]) == pytest.approx(
            ranked["metrics"]["f1_weighted"]["mean"]
        )
    screen(tab, "run-per-recording")
    # ranking by another metric keeps the aggregation, and so does a classifier's page
    page.locator("#leaderboard-table th a", has_text="accuracy").click()
    page.wait_for_url(re.compile(r"metric=accuracy.*aggregate=recording"))
    expect(page.locator("#leaderboard")).to_contain_text(RESCORED)
    # and so does the CSV: ranked by accuracy, scored per recording
    expect(csv_link).to_have_attribute(
        "href", f"/api/runs/{takes}/leaderboard?format=csv&metric=accuracy&aggregate=recording"
    )
    with page.expect_download() as downloading:
        csv_link.click()
    by_accuracy = api.get(
        f"/api/runs/{takes}/leaderboard", params={"aggregate": "recording", "metric": "accuracy"}
    ).json()
    rows = list(csv.DictReader(io.StringIO(downloading.value.path().read_text(encoding="utf-8"))))
    assert [row["classifier"] for row in rows] == [
        row["classifier"] for row in by_accuracy["leaderboard"]
    ]
    assert list(rows[0])[3] == "accuracy_mean"  # the ranking metric's column first
    # and the baseline the marks are against
    page.goto(f"{service.url}/runs/{takes}?baseline=ridge")
    expect(page.locator("#leaderboard-table")).to_have_attribute("data-baseline", "ridge")
    expect(csv_link).to_have_attribute(
        "href", f"/api/runs/{takes}/leaderboard?format=csv&baseline=ridge"
    )
    page.goto(f"{service.url}/runs/{takes}?metric=accuracy&aggregate=recording")
    page.locator("#leaderboard-table td a", has_text="nb").click()
    page.wait_for_url(re.compile(r"/classifiers/nb\?.*aggregate=recording"))
    nb = next(row for row in board["leaderboard"] if row["classifier"] == "nb")
    scores = page.locator("#classifier")
    expect(scores).to_contain_text(f"{nb['metrics']['accuracy']['mean']:.4f}")

    # a run whose recordings hold several labels: as it scored, and why not per recording
    page.goto(f"{service.url}/runs/{mixed}?aggregate=recording")
    expect(page.locator("#leaderboard .refused")).to_contain_text(
        "not scored per recording: 1 recording(s) hold windows of several values of 'gesture'"
    )
    expect(page.locator("select[name=aggregate]")).to_have_value("window")
    expect(page.locator("#leaderboard")).not_to_contain_text(RESCORED)
