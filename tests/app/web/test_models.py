"""A model's page in a real headless Chromium against a real service with a write key and
a read key: the versions of a name with their scores and runs; promote, roll back, set and
delete aliases; the ONNX twin made by a job and downloaded.  The read key sees the same
pages, and every button that writes is refused with the service's own message."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import httpx
import pytest
from playwright.sync_api import Page, expect

from tests.support.browser import Tab, screen
from tests.support.service import Server, finished, servers
from tests.support.synthetic import touch_arff

WRITE_KEY = "writer-key-of-the-lab-0123"
READ_KEY = "reader-key-of-the-lab-4567"
#: A job takes seconds; the first one also pays for the worker's imports.
TIMEOUT = 120_000


@pytest.fixture(scope="module")
def service(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    """One keyed service for the module: a data set, a finished run, and two versions of
    the model ``toucher`` (the run's best, then a random forest, which has an ONNX
    converter, on the data set)."""
    folder = tmp_path_factory.mktemp("models")
    builds = servers(f"sqlite:///{folder / 'touchbench.db'}", folder)
    server = next(builds)(api_keys=f"writer:write:{WRITE_KEY},reader:read:{READ_KEY}")
    server.client.headers["X-API-Key"] = WRITE_KEY
    data = touch_arff(folder / "touch.arff", n=60, with_place=False)
    with data.open("rb") as handle:
        assert server.client.post(
            "/api/datasets", files={"file": ("touch.arff", handle)}
        ).is_success
    run = server.client.post(
        "/api/runs", json={"dataset": "touch", "classifiers": ["nb", "zeror"], "folds": 3}
    ).json()
    assert server.wait_for(f"/api/runs/{run['id']}", finished)["status"] == "done"
    for body in (
        {"run": run["id"], "name": "toucher"},
        {"dataset": "touch", "classifier": "rf", "name": "toucher"},
    ):
        job = server.client.post("/api/models", json=body).json()["job"]
        assert server.wait_for(f"/api/jobs/{job}", finished)["status"] == "done"
    yield server
    next(builds, None)


def _versions(server: Server) -> dict[int, dict[str, Any]]:
    models = server.client.get("/api/models").json()["models"]
    return {m["version"]: m for m in models if m["name"] == "toucher"}


def _open(page: Page, server: Server, key: str, model: int) -> None:
    page.goto(f"{server.url}/models/{model}")
    box = page.locator("#api-key-input")
    box.fill(key)
    box.press("Enter")
    expect(page.locator("#versions-table tbody tr")).to_have_count(2)


def _aliases(page: Page, version: int) -> list[str]:
    row = page.locator(f"#versions-table tr[data-version='{version}'] .alias")
    return [row.nth(i).get_attribute("data-alias") or "" for i in range(row.count())]


def test_versions_aliases_and_the_onnx_twin(projector_tab: Tab, service: Server) -> None:
    tab, page = projector_tab, projector_tab.page
    versions = _versions(service)
    _open(page, service, WRITE_KEY, versions[2]["id"])

    # each version with its score in the run it came from
    first = page.locator("#versions-table tr[data-version='1']")
    board = service.client.get(f"/api/runs/{versions[1]['run_id']}/leaderboard").json()
    mean = next(r for r in board["leaderboard"] if r["classifier"] == versions[1]["classifier"])
    score = mean["metrics"][board["metric"]]["mean"]
    expect(first).to_contain_text(f"{board['metric']} {score:.4f}")
    expect(first.get_by_role("link", name=f"run {versions[1]['run_id']}")).to_be_visible()
    expect(page.locator("#versions-table tr[data-version='2']")).to_contain_text("rf")

    # promote version 1, then version 2: the alias moves; roll back: it moves back
    for version in (1, 2):
        page.get_by_role("button", name=f"promote toucher@{version} to champion").click()
        expect(page.locator(f"#versions-table tr[data-version='{version}'] .alias")).to_have_text(
            "champion×"
        )
        assert "champion" in _versions(service)[version]["aliases"]
    assert _aliases(page, 1) == []
    page.get_by_role("button", name="Roll the champion back").click()
    expect(
        page.locator("#versions-table tr[data-version='1'] [data-alias='champion']")
    ).to_be_visible()
    assert "champion" not in _aliases(page, 2)

    # set an alias on the version shown, then delete it
    form = page.locator("form[data-action=alias]")
    form.get_by_label("alias").fill("staging")
    form.get_by_role("button", name="Point the alias").click()
    expect(
        page.locator("#versions-table tr[data-version='2'] [data-alias='staging']")
    ).to_be_visible()
    screen(tab, "model-versions")
    page.get_by_role("button", name="delete the alias staging of toucher@2").click()
    expect(page.locator("[data-alias='staging']")).to_have_count(0)
    assert "staging" not in _versions(service)[2]["aliases"]

    # the ONNX twin of version 2 (the forest): made by a job, then downloaded
    page.get_by_role("button", name="Make the ONNX twin").click()
    job = page.locator("#onnx-job .job-box")
    expect(job.locator(".status")).to_have_text("done", timeout=TIMEOUT)
    with page.expect_download() as download:
        job.get_by_role("link", name="Download the ONNX twin").click()
    saved = download.value.path()
    stored = service.client.get(f"/api/models/{versions[2]['id']}/onnx").content
    assert saved is not None and saved.read_bytes() == stored and len(stored) > 100
    page.reload()
    expect(page.get_by_role("link", name="Download the ONNX twin")).to_be_visible()


def test_a_read_key_sees_the_pages_but_every_write_is_refused(
    projector_tab: Tab, service: Server
) -> None:
    page = projector_tab.page
    versions = _versions(service)
    before = {v: m["aliases"] for v, m in versions.items()}
    refusal = "the API key 'reader' is a read key; this needs a write key"
    _open(page, service, READ_KEY, versions[1]["id"])
    outcome = page.locator("#model .outcome").first
    for button in (
        page.get_by_role("button", name="promote toucher@2 to champion"),
        page.get_by_role("button", name="Roll the champion back"),
        page.locator("[data-alias] button").first,
    ):
        button.click()
        expect(outcome).to_have_text(refusal)
        page.evaluate("document.querySelector('#model .outcome').replaceChildren()")
    form = page.locator("form[data-action=alias]")
    form.get_by_label("alias").fill("staging")
    form.get_by_role("button", name="Point the alias").click()
    expect(form.locator(".outcome")).to_have_text(refusal)
    assert {v: m["aliases"] for v, m in _versions(service).items()} == before
    expect(page.locator("#api-key-state")).to_have_text("key in use (this tab)")  # not "wrong"

    # a run and an answer: the forms show, the service refuses them
    run_id = versions[1]["run_id"]
    page.goto(f"{service.url}/runs/new?dataset=touch")
    run_form = page.locator("form[data-action=start-run]")
    run_form.get_by_label("classifiers").fill("nb")
    run_form.get_by_role("button", name="Start the run").click()
    expect(run_form.locator(".outcome")).to_have_text(refusal)
    page.goto(f"{service.url}/runs/{run_id}")
    ablation = page.locator("form[data-url='/api/jobs/ablation']")
    ablation.get_by_role("button", name="Start the ablation").click()
    expect(ablation.locator(".outcome")).to_have_text(refusal)
    expect(page.get_by_role("button", name="Train its best classifier")).to_be_visible()
    page.get_by_role("button", name="Train its best classifier").click()
    expect(page.locator("#progress .outcome")).to_have_text(refusal)
    bare = httpx.get(f"{service.url}/api/runs", headers={"X-API-Key": WRITE_KEY}).json()
    assert len(bare["runs"]) == 1
    jobs = httpx.get(f"{service.url}/api/jobs", headers={"X-API-Key": WRITE_KEY}).json()["jobs"]
    assert {job["kind"] for job in jobs} <= {"train", "export"}
