"""The recording-session form in a real headless Chromium against a real service: the
extractors and their options come from the service's listing; a simulated session (two
takes and their labels) is uploaded, the extraction job's progress shows, and the new data
set's page opens with what the extraction did; bad input is refused in the page first and
by the service after, both naming the request's field."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
from playwright.sync_api import expect

from tests.support.browser import Tab, screen
from tests.support.service import Server, finished, servers
from touchbench.app.services.simulation import write_labels, write_session

#: An extraction takes seconds; the first one also pays for the worker's imports.
JOB_TIMEOUT = 180_000


@pytest.fixture(scope="module")
def service(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    """One service for the module's tests."""
    folder = tmp_path_factory.mktemp("sessions")
    builds = servers(f"sqlite:///{folder / 'touchbench.db'}", folder)
    build = next(builds)
    yield build()
    next(builds, None)


@pytest.fixture(scope="module")
def session(tmp_path_factory: pytest.TempPathFactory) -> tuple[list[Path], Path]:
    """Two simulated three-microphone takes and a labels file that also names a take not
    uploaded (a label not matched)."""
    folder = tmp_path_factory.mktemp("takes")
    paths, rows = [], []
    for i in range(2):
        path, touches = write_session(folder, f"take{i + 1}", n_touches=6, seed=i)
        paths.append(path)
        rows += [(path.name, *touch) for touch in touches]
    rows.append(("take9.wav", 0.5, 0.6, "tap", "head"))
    return paths, write_labels(folder / "labels.csv", rows)


def test_a_session_uploaded_from_the_page_becomes_a_data_set(
    projector_tab: Tab, service: Server, session: tuple[list[Path], Path]
) -> None:
    tab, page = projector_tab, projector_tab.page
    page.goto(service.url + "/")
    page.get_by_role("link", name="Upload a recording session").click()
    page.wait_for_url("**/recordings/new")
    form = page.locator("#session-upload")

    # the extractors are the service's own, each option an input with its default and help
    listing = service.client.get("/api/extractors").json()
    names = [e["name"] for e in listing["extractors"]]
    extractor = form.get_by_label("extractor", exact=True)
    expect(extractor).to_be_visible()
    assert extractor.locator("option").evaluate_all("os => os.map(o => o.value)") == names
    uc3m = next(e for e in listing["extractors"] if e["name"] == "uc3m-audio")
    shown = form.locator("[data-owner='extractor:uc3m-audio']")
    expect(shown).to_be_visible()
    for option in uc3m["options"]:
        field = shown.locator(f"[data-option='{option['name']}']")
        expect(field).to_be_visible()
        helped = page.locator(f"#{field.get_attribute('aria-describedby')}")
        expect(helped).to_contain_text(option["meaning"])
    other = next(name for name in names if name != "uc3m-audio")
    extractor.select_option(other)
    expect(shown).to_be_hidden()
    expect(form.locator(f"[data-owner='extractor:{other}']")).to_be_visible()
    extractor.select_option("uc3m-audio")
    time_unit = form.get_by_label("time unit")
    assert time_unit.locator("option").evaluate_all("os => os.map(o => o.value)") == [
        "auto", "s", "ms", "us", "ns",
    ]  # fmt: skip
    expect(time_unit).to_have_value("auto")  # the request's default

    # checked in the page first, naming the request's field
    paths, labels = session
    form.locator("input[name=recordings]").set_input_files([str(p) for p in paths])
    form.locator("input[name=labels]").set_input_files(str(labels))
    form.get_by_label("samplerate").fill("-5")
    form.get_by_role("button", name="Upload and extract").click()
    expect(form.locator(".outcome")).to_contain_text("samplerate: Input should be greater than 0")
    expect(form.get_by_label("samplerate")).to_have_attribute("aria-invalid", "true")
    form.get_by_label("samplerate").fill("")

    # then by the service: an option's bad value, as the service words it
    snr = form.locator("[data-owner='events:snr']")  # the extractor's own event detection
    expect(snr).to_be_visible()
    expect(form.locator("[data-owner='events:dbscan']")).to_be_hidden()
    option_box = snr.locator("[data-option='threshold']")
    expect(option_box).to_have_attribute("placeholder", "10.0")
    option_box.fill("0")
    form.get_by_role("button", name="Upload and extract").click()
    expect(form.locator(".outcome")).to_contain_text("threshold")
    expect(form.locator(".outcome")).to_contain_text("(body.options)")
    assert service.client.get("/api/jobs").json()["jobs"] == []  # refused before a job
    option_box.fill("")

    form.get_by_label("name").fill("robot-take")
    page.evaluate("window.scrollTo(0, 0)")
    screen(tab, "session-upload")
    form.get_by_role("button", name="Upload and extract").click()
    expect(form.locator(".outcome")).to_contain_text("Extraction job")
    page.wait_for_url("**/datasets/*?job=*", timeout=JOB_TIMEOUT)

    # the new data set's page, with what the extraction did
    expect(page.locator("#dataset h1")).to_contain_text("robot-take")
    job = service.client.get("/api/jobs").json()["jobs"][-1]
    assert job["status"] == "done" and job["params"]["recordings"] == [p.name for p in paths]
    result = job["result"]
    notes = page.locator("#extraction-notes")
    expect(notes).to_contain_text(
        f"{result['events_found']} events found, {result['events_labelled']} labelled and kept"
    )
    for line in result["warnings"] + result["notes"]:
        expect(notes).to_contain_text(line)
    assert any("take9.wav" in line for line in result["warnings"] + result["notes"]), result
    described = service.client.get("/api/datasets/robot-take").json()
    assert described["targets"] == ["gesture", "place"]
    screen(tab, "session-dataset")


def test_a_model_of_the_session_predicts_an_uploaded_raw_recording(
    tab: Tab, service: Server, session: tuple[list[Path], Path]
) -> None:
    api = service.client
    if not any(d["name"] == "robot-take" for d in api.get("/api/datasets").json()["datasets"]):
        pytest.skip("needs the data set the upload test makes")
    job = api.post(
        "/api/models",
        json={"dataset": "robot-take", "classifier": "nb", "target": "gesture", "name": "feeler"},
    ).json()["job"]
    model = service.wait_for(f"/api/jobs/{job}", finished)
    assert model["status"] == "done", model
    page = tab.page
    page.goto(f"{service.url}/models/{model['result']['id']}")
    form = page.locator("form[data-action=predict-file]")
    expect(form).to_contain_text("or a raw recording")
    take = session[0][0]
    form.locator("input[name=file]").set_input_files(str(take))
    form.get_by_role("button", name="Predict the file").click()
    with take.open("rb") as handle:
        answer = api.post(
            f"/api/models/{model['result']['id']}/predict/file", files={"file": (take.name, handle)}
        ).json()
    rows = page.locator("#predictions tbody tr")
    expect(rows).to_have_count(len(answer["predictions"]), timeout=JOB_TIMEOUT)
    assert len(answer["predictions"]) >= 3
    labels = [p["gesture"] for p in answer["predictions"]]
    expect(rows.locator("td:nth-child(2)")).to_have_text(labels)
