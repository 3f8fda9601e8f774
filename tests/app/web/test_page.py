"""The web page in a real headless Chromium against a real ``touchbench serve``: upload data
sets, start a run from the form, watch it finish, rank by another metric, change the
baseline, open a classifier's confusion matrix, a data set's class distribution, the
comparison across runs, train the best classifier and predict with it; then the same
service behind an API key.  What the page shows is checked against the JSON API and the
CLI, and its figures by the text of their SVG."""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path

import httpx
import pytest
from playwright.sync_api import expect

from tests.support.browser import Tab, figure_texts
from tests.support.cli_runner import run_cli
from tests.support.service import Server, finished
from tests.support.synthetic import touch_arff

CLASSIFIERS = ["nb", "zeror", "j48"]
#: A run takes seconds; the first one also pays for the worker's imports.
RUN_TIMEOUT = 180_000


def _board_order(tab: Tab) -> list[str]:
    rows = tab.page.locator("#leaderboard-table tbody tr")
    return [rows.nth(i).get_attribute("data-classifier") or "" for i in range(rows.count())]


def _upload(tab: Tab, path: Path, name: str) -> None:
    form = tab.page.locator("#upload")
    form.locator("input[name=file]").set_input_files(str(path))
    form.locator("input[name=name]").fill(name)
    form.locator("button[type=submit]").click()
    expect(form.locator(".outcome")).to_contain_text(f"Imported '{name}'")
    expect(tab.page.locator("#datasets-list")).to_contain_text(name)


@pytest.mark.slow
def test_a_researcher_benchmarks_compares_and_predicts_in_the_browser(
    capsys: pytest.CaptureFixture[str],
    make_sqlite_server: Callable[..., Server],
    tab: Tab,
    tmp_path: Path,
) -> None:
    server = make_sqlite_server()
    page, api = tab.page, server.client

    # data sets: upload two through the form
    page.goto(server.url + "/")
    expect(page.locator("#runs-list")).to_contain_text("No run yet")
    _upload(tab, touch_arff(tmp_path / "touch.arff", n=120), "touch")
    _upload(tab, touch_arff(tmp_path / "other.arff", n=90, seed=3, with_place=False), "other")
    tab.shot("uploaded")

    # a run from the form: one target of a multi-target data set, three classifiers
    touch_row = page.locator("#datasets-list tr", has_text="touch")
    touch_row.get_by_role("link", name="Benchmark").click()
    form = page.locator("form[data-action=start-run]")
    expect(form.locator("select[name=dataset]")).to_have_value("touch")
    form.locator("select[name=target]").select_option("gesture")
    form.locator("input[name=classifiers]").fill(", ".join(CLASSIFIERS))
    form.locator("input[name=folds]").fill("3")
    tab.shot("run-form")
    form.locator("button[type=submit]").click()
    page.wait_for_url(re.compile(r"/runs/\d+$"))
    run_id = int(page.url.rsplit("/", 1)[1])
    tab.shot("run-started")

    # live progress until done, then the leaderboard and the plots
    expect(page.locator("#run-status")).to_have_text("done", timeout=RUN_TIMEOUT)
    expect(page.locator("#run-tasks")).to_have_text("9 of 9 tasks")
    expect(page.locator("#leaderboard-table tbody tr")).to_have_count(3)
    expect(page.locator("#plots figure img").first).to_be_visible()
    run = api.get(f"/api/runs/{run_id}").json()
    assert (run["status"], run["targets"], run["classifiers"]) == ("done", ["gesture"], CLASSIFIERS)
    board = api.get(f"/api/runs/{run_id}/leaderboard").json()
    assert _board_order(tab) == [row["classifier"] for row in board["leaderboard"]]
    folds = figure_texts(page.locator("#plots figure img").first.get_attribute("src"))
    assert "f1_weighted per fold (higher is better; bar: mean)" in folds
    assert set(CLASSIFIERS) <= set(folds)
    tab.shot("run-done")

    # rank by another metric: the order and marks the API gives for it
    page.locator("#leaderboard-table thead a", has_text="kappa").click()
    page.wait_for_url(re.compile(r"metric=kappa"))
    table = page.locator("#leaderboard-table")
    expect(table).to_have_attribute("data-metric", "kappa")
    expect(page.locator("#leaderboard-table th.sorted")).to_contain_text("kappa")
    by_kappa = api.get(f"/api/runs/{run_id}/leaderboard", params={"metric": "kappa"}).json()
    assert _board_order(tab) == [row["classifier"] for row in by_kappa["leaderboard"]]
    tab.shot("ranked-by-kappa")

    # another baseline: zeror, which the others beat
    page.locator("select[name=baseline]").select_option("zeror")
    page.wait_for_url(re.compile(r"baseline=zeror"))
    expect(table).to_have_attribute("data-baseline", "zeror")
    expect(table).to_have_attribute("data-metric", "kappa")  # the ranking metric is kept
    against_zeror = api.get(
        f"/api/runs/{run_id}/leaderboard", params={"metric": "kappa", "baseline": "zeror"}
    ).json()
    for row in against_zeror["leaderboard"]:
        mark = page.locator(f"#leaderboard-table tr[data-classifier='{row['classifier']}'] td.mark")
        expect(mark).to_have_text("(base)" if row["classifier"] == "zeror" else row["mark"])
    assert against_zeror["summary"]["better"] >= 1  # some mark shows, or the check is empty
    tab.shot("baseline-zeror")

    # a classifier's confusion matrix (labels from the schema) and its folds
    page.locator("#leaderboard-table a", has_text="j48").click()
    page.wait_for_url(re.compile(rf"/runs/{run_id}/classifiers/j48"))
    expect(page.locator("#classifier h1")).to_contain_text(f"j48 in run {run_id}")
    confusion = figure_texts(page.locator("#classifier figure img").first.get_attribute("src"))
    assert {"tap", "slap", "stroke", "predicted", "true"} <= set(confusion)
    assert "j48, summed over 3 folds" in " ".join(confusion)  # the title, wrapped
    expect(page.locator("table", has_text="fold 1").locator("tbody tr")).to_have_count(3)
    # the metric and baseline chosen on the leaderboard follow to the classifier's page
    expect(page.locator("#classifier .meta")).to_contain_text("by kappa")
    expect(page.locator("#classifier th", has_text="zeror (baseline)")).to_be_visible()
    tab.shot("confusion-j48")

    # the data set: schema and class distribution per target
    page.goto(f"{server.url}/datasets/touch")
    expect(page.locator("#dataset h1")).to_contain_text("touch")
    counts = figure_texts(page.locator("#dataset figure img").first.get_attribute("src"))
    assert {"gesture (120 instances)", "place (120 instances)"} <= set(counts)
    expect(page.locator("caption", has_text="gesture")).to_be_visible()
    tab.shot("dataset")

    # a second data set's run (over the API), then the comparison across both
    second = api.post(
        "/api/runs",
        json={"dataset": "other", "target": "gesture", "classifiers": CLASSIFIERS, "folds": 3},
    ).json()["id"]
    assert server.wait_for(f"/api/runs/{second}", finished)["status"] == "done"
    page.goto(f"{server.url}/compare")
    for chosen in (run_id, second):
        page.locator(f"input[name=runs][value='{chosen}']").check()
    page.get_by_role("button", name="Compare").click()
    page.wait_for_url(re.compile(r"/compare\?runs="))
    expect(page.locator(".comparison h2")).to_contain_text("Comparison across 2 data sets")
    expected = run_cli(
        capsys, server.database_url, "compare", str(run_id), str(second), "--json"
    ).json()
    diagram = figure_texts(page.locator(".comparison figure img").get_attribute("src"))
    for entry in expected["classifiers"]:
        assert f"{entry['classifier']} ({entry['average_rank']:.2f})" in diagram
    assert f"CD = {expected['nemenyi']['critical_difference']:.3f}" in diagram
    tab.shot("compare")

    # train the run's best classifier from its page, then predict one instance
    page.goto(f"{server.url}/runs/{run_id}")
    page.get_by_role("button", name="Train its best classifier").click()
    page.wait_for_url(re.compile(r"/#models$"))
    best = board["leaderboard"][0]["classifier"]
    model_row = page.locator("#models-list tbody tr").first
    expect(model_row).to_be_visible(timeout=RUN_TIMEOUT)
    expect(model_row.locator("td").nth(2)).to_have_text(best)
    model_row.get_by_role("link").first.click()
    predict = page.locator("form[data-action=predict]")
    instance = {"f0": 4.1, "f1": 0.2, "f2": -0.3, "f3": 0.5}
    for name, value in instance.items():
        predict.locator(f"input[data-feature={name}]").fill(str(value))
    predict.locator("select[data-feature=mic]").select_option("right")
    predict.locator("button[type=submit]").click()
    shown = page.locator("#predictions tbody tr")
    expect(shown).to_have_count(1, timeout=60_000)  # the first prediction loads the model
    model_id = predict.get_attribute("data-model")
    answer = api.post(
        f"/api/models/{model_id}/predict", json={"instances": [{**instance, "mic": "right"}]}
    ).json()["predictions"][0]
    expect(shown.locator("td").nth(1)).to_have_text(answer["gesture"])
    expect(shown.locator("td").nth(2)).to_have_text(
        f"{answer['probabilities']['gesture'][answer['gesture']]:.3f}"
    )
    tab.shot("predicted")
    assert len(tab.shots) == 10


def test_the_page_with_an_api_key(
    capsys: pytest.CaptureFixture[str],
    make_sqlite_server: Callable[..., Server],
    tab: Tab,
    tmp_path: Path,
) -> None:
    key = "s3cret-page-key-of-the-lab"
    server = make_sqlite_server(api_key=key)
    data = touch_arff(tmp_path / "touch.arff", n=60)
    assert run_cli(capsys, server.database_url, "import", str(data), "--name", "guarded").code == 0

    # without the key: frames answer, data does not
    bare = httpx.Client(base_url=server.url, timeout=30)
    try:
        frame = bare.get("/")
        assert frame.status_code == 200 and "guarded" not in frame.text
        assert bare.get("/fragments/datasets").status_code == 401
        wrong = bare.get("/fragments/datasets", headers={"X-API-Key": key + "x"})
        assert wrong.status_code == 403
        assert bare.get("/datasets/guarded").status_code == 200
        assert bare.get("/fragments/datasets/guarded").status_code == 401
    finally:
        bare.close()

    page = tab.page
    page.goto(server.url + "/")
    expect(page.locator("#datasets-list")).to_contain_text("needs an API key")
    expect(page.locator("#api-key-state")).to_have_text("this service needs a key")
    tab.shot("key-needed")

    key_box = page.locator("#api-key-input")
    key_box.fill("not-the-key")
    key_box.press("Enter")
    expect(page.locator("#datasets-list")).to_contain_text("The API key is wrong")
    key_box.fill(key)
    key_box.press("Enter")
    expect(page.locator("#datasets-list")).to_contain_text("guarded")
    expect(page.locator("#api-key-state")).to_have_text("key in use (this tab)")

    # the key stays for the tab: another page loads, and an upload goes through
    page.locator("#datasets-list a", has_text="guarded").click()
    expect(page.locator("#dataset h1")).to_contain_text("guarded")
    page.goto(server.url + "/")
    _upload(tab, touch_arff(tmp_path / "more.arff", n=45, seed=5), "more")
    tab.shot("key-in-use")

    page.locator("#api-key-forget").click()
    expect(page.locator("#datasets-list")).to_contain_text("needs an API key")
    assert page.evaluate("sessionStorage.getItem('touchbench.apiKey')") is None


#: Holds back the body of every 403 answer for a while, as a slow network would.
SLOW_REFUSALS = """
const json = Response.prototype.json;
Response.prototype.json = function () {
  const body = json.call(this);
  if (this.status !== 403) return body;
  return new Promise((resolve) => setTimeout(() => resolve(body), 1500));
};
"""


def test_a_refusal_of_the_old_key_read_late_does_not_hide_the_new_one(
    make_sqlite_server: Callable[..., Server], tab: Tab
) -> None:
    key = "s3cret-page-key-of-the-lab"
    server = make_sqlite_server(api_key=key)
    page = tab.page
    page.add_init_script(SLOW_REFUSALS)
    page.goto(server.url + "/")
    expect(page.locator("#api-key-state")).to_have_text("this service needs a key")

    # a wrong key, then the right one before the refusals of the wrong one are read
    key_box = page.locator("#api-key-input")
    key_box.fill("not-the-key")
    key_box.press("Enter")
    key_box.fill(key)
    key_box.press("Enter")
    expect(page.locator("#datasets-list")).to_contain_text("No data set")
    expect(page.locator("#api-key-state")).to_have_text("key in use (this tab)")
    page.wait_for_timeout(2500)  # every held-back refusal of the wrong key has been read
    expect(page.locator("#api-key-state")).to_have_text("key in use (this tab)")
    expect(page.locator("#datasets-list")).not_to_contain_text("wrong")
