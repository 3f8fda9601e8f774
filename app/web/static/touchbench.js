// touchbench's web page: loads the server-rendered fragments into their regions with the
// API key (kept in this tab's session storage), polls the ones that say so, and carries out
// actions (upload, start a run, cancel, train, predict) through the JSON API.
// No framework, no build step; everything shown is built with textContent or comes from
// the server's autoescaped templates.
"use strict";

const KEY = "touchbench.apiKey";

// A form's controls shadow its properties by name (a control called "dataset" or "target"
// hides form.dataset or form.target), so forms are read through the prototypes.
const attribute = (element, name) => Element.prototype.getAttribute.call(element, name);
const find = (element, selector) => Element.prototype.querySelector.call(element, selector);
const findAll = (element, selector) => Element.prototype.querySelectorAll.call(element, selector);

function apiHeaders(extra = {}) {
  const key = sessionStorage.getItem(KEY);
  return key ? { ...extra, "X-API-Key": key } : extra;
}

// Whether the key a request was sent with is still the tab's key: an answer to an older key
// (a region still loading when a new key was entered) must not overwrite the newer state.
const keyStill = (sent) => sessionStorage.getItem(KEY) === sent;

async function call(url, options = {}) {
  const sent = sessionStorage.getItem(KEY);
  const response = await fetch(url, { ...options, headers: apiHeaders(options.headers) });
  if ((response.status === 401 || response.status === 403) && keyStill(sent)) {
    showKeyState(response.status);
  }
  return response;
}

async function problem(response) {
  // One line from the JSON error body the service always answers.
  try {
    const body = await response.json();
    const error = body.error || {};
    const where = error.where ? ` (${error.where})` : "";
    if (response.status === 401) return "This service needs an API key: enter it at the top.";
    if (response.status === 403) return "The API key is wrong: enter the service's key at the top.";
    return `${error.message || response.statusText}${where}`;
  } catch (_) {
    return `${response.status} ${response.statusText}`;
  }
}

function showKeyState(status) {
  const state = document.getElementById("api-key-state");
  const form = document.getElementById("api-key");
  const key = sessionStorage.getItem(KEY);
  form.classList.toggle("needed", status === 401 || status === 403);
  if (status === 401) state.textContent = "this service needs a key";
  else if (status === 403) state.textContent = "wrong key";
  else state.textContent = key ? "key in use (this tab)" : "";
}

function message(element, text, kind = "error") {
  element.replaceChildren();
  const line = document.createElement("p");
  line.className = kind;
  line.textContent = text;
  element.append(line);
}

// ------------------------------------------------------------------------------ regions

function regionUrl(region) {
  let url = region.dataset.src;
  if (region.hasAttribute("data-forward") && location.search.length > 1) {
    url += (url.includes("?") ? "&" : "?") + location.search.slice(1);
  }
  return url;
}

const timers = new Map();

async function load(region) {
  clearTimeout(timers.get(region));
  const sent = sessionStorage.getItem(KEY);
  let response;
  try {
    response = await call(regionUrl(region));
    if (!keyStill(sent)) return; // the key changed meanwhile: its own load is underway
  } catch (error) {
    message(region, `The service did not answer (${error.message}); retrying.`);
    timers.set(region, setTimeout(() => load(region), 3000));
    return;
  }
  if (!response.ok) {
    message(region, await problem(response));
    region.dataset.loaded = "error";
    return;
  }
  const parsed = new DOMParser().parseFromString(await response.text(), "text/html");
  const before = region.querySelector("[data-state]");
  const previous = before ? before.dataset.state : null;
  const wasFinal = Boolean(region.querySelector("[data-final]"));
  region.replaceChildren(...parsed.body.childNodes);
  region.dataset.loaded = "yes";
  const after = region.querySelector("[data-state]");
  if (previous !== null && after && after.dataset.state !== previous) {
    document.querySelectorAll(`[data-follows="${region.id}"]`).forEach(load);
    if (region.querySelector("[data-final]") && !wasFinal) {
      document.querySelectorAll(`[data-follows-final="${region.id}"]`).forEach(load);
    }
  }
  const poll = region.querySelector("[data-poll]");
  if (poll) timers.set(region, setTimeout(() => load(region), Number(poll.dataset.poll)));
  fillTargets(region);
}

function loadAll() {
  document.querySelectorAll(".region[data-src]").forEach(load);
}

// ------------------------------------------------------------------------------ actions

async function upload(form, outcome) {
  const data = new FormData(form);
  for (const name of ["name", "targets"]) if (!data.get(name)) data.delete(name);
  const response = await call("/api/datasets", { method: "POST", body: data });
  if (!response.ok) return message(outcome, await problem(response));
  const result = await response.json();
  const what = result.created ? "Imported" : "Already stored as";
  message(outcome, `${what} '${result.name}': ${result.n_instances} instances, ` +
    `${result.n_features} features, targets ${result.targets.join(", ")}.`, "ok");
  HTMLFormElement.prototype.reset.call(form);
  document.querySelectorAll("#datasets-list").forEach(load);
}

async function startRun(form, outcome) {
  const data = new FormData(form);
  const body = {
    dataset: data.get("dataset"),
    folds: Number(data.get("folds")),
    repeats: Number(data.get("repeats")),
    seed: Number(data.get("seed")),
  };
  if (data.get("target")) body.target = data.get("target");
  if (data.get("choice") === "classifiers") {
    body.classifiers = String(data.get("classifiers")).split(/[\s,]+/).filter(Boolean);
    if (!body.classifiers.length) return message(outcome, "Give at least one classifier id.");
  } else {
    body.suite = data.get("suite");
  }
  const response = await call("/api/runs", {
    method: "POST",
    headers: { "Content-Type": "application/json" },
    body: JSON.stringify(body),
  });
  if (!response.ok) return message(outcome, await problem(response));
  const run = await response.json();
  location.assign(`/runs/${run.id}`);
}

function instanceOf(form) {
  const instance = {};
  for (const field of findAll(form, "[data-kind]")) {
    if (field.value === "") {
      instance[field.dataset.feature] = null; // a value not known: a missing value
      continue;
    }
    const value = field.dataset.kind === "numeric" ? Number(field.value) : field.value;
    instance[field.dataset.feature] = value;
  }
  return instance;
}

async function predict(form, file) {
  const target = document.getElementById("predictions");
  const url = `/api/models/${attribute(form, "data-model")}/predict` + (file ? "/file" : "");
  const options = file
    ? { method: "POST", body: new FormData(form) }
    : {
        method: "POST",
        headers: { "Content-Type": "application/json" },
        body: JSON.stringify({ instances: [instanceOf(form)] }),
      };
  message(target, "Predicting…", "note");
  const response = await call(url, options);
  if (!response.ok) return message(target, await problem(response));
  showPredictions(target, await response.json());
}

function cell(row, text, tag = "td") {
  const element = document.createElement(tag);
  element.textContent = text;
  row.append(element);
  return element;
}

function showPredictions(target, report) {
  target.replaceChildren();
  const heading = document.createElement("h2");
  heading.textContent = `Predictions of ${report.model} (${report.predictions.length})`;
  target.append(heading);
  for (const [name, value] of Object.entries(report.accuracy || {})) {
    const line = document.createElement("p");
    line.textContent = `Accuracy on ${name}: ${value.toFixed(4)}`;
    target.append(line);
  }
  for (const warning of report.warnings || []) {
    const line = document.createElement("p");
    line.className = "note";
    line.textContent = warning;
    target.append(line);
  }
  const table = document.createElement("table");
  table.className = "list compact";
  const head = document.createElement("tr");
  cell(head, "instance", "th");
  for (const name of report.targets) {
    cell(head, name, "th");
    cell(head, "probability", "th");
  }
  table.createTHead().append(head);
  const body = table.createTBody();
  for (const prediction of report.predictions.slice(0, 500)) {
    const row = document.createElement("tr");
    cell(row, String(prediction.instance));
    for (const name of report.targets) {
      const label = prediction[name];
      cell(row, label === null || label === undefined ? "?" : String(label));
      const probabilities = (prediction.probabilities || {})[name] || {};
      const p = probabilities[label];
      cell(row, typeof p === "number" ? p.toFixed(3) : "-").className = "num";
    }
    body.append(row);
  }
  target.append(table);
}

async function post(button) {
  const box = button.closest(".region") || document.body;
  const outcome = box.querySelector(".outcome") || box;
  const options = { method: "POST" };
  if (button.dataset.body) {
    options.headers = { "Content-Type": "application/json" };
    options.body = button.dataset.body;
  }
  button.disabled = true;
  const response = await call(button.dataset.post, options);
  button.disabled = false;
  if (!response.ok) return message(outcome, await problem(response));
  if (button.dataset.then) return location.assign(button.dataset.then);
  loadAll();
}

async function download(link) {
  const response = await call(link.getAttribute("href"));
  if (!response.ok) return alert(await problem(response));
  const url = URL.createObjectURL(await response.blob());
  const anchor = document.createElement("a");
  anchor.href = url;
  anchor.download = link.dataset.download;
  document.body.append(anchor);
  anchor.click();
  anchor.remove();
  setTimeout(() => URL.revokeObjectURL(url), 10000);
}

function fillTargets(root) {
  for (const select of root.querySelectorAll("select[data-targets-of]")) {
    const source = find(select.form, `select[name="${select.dataset.targetsOf}"]`);
    const refill = () => {
      const chosen = source.selectedOptions[0];
      const targets = chosen ? chosen.dataset.targets.split(",").filter(Boolean) : [];
      select.replaceChildren(select.options[0]);
      for (const name of targets) {
        const option = document.createElement("option");
        option.value = name;
        option.textContent = name;
        select.append(option);
      }
      if (targets.length === 1) select.value = targets[0];
    };
    source.addEventListener("change", refill);
    refill();
  }
}

// ------------------------------------------------------------------------------ wiring

const ACTIONS = {
  upload: upload,
  "start-run": startRun,
  predict: (form) => predict(form, false),
  "predict-file": (form) => predict(form, true),
};

document.addEventListener("submit", (event) => {
  const form = event.target;
  if (attribute(form, "id") === "api-key") {
    event.preventDefault();
    const input = document.getElementById("api-key-input");
    const key = input.value.trim();
    if (key) sessionStorage.setItem(KEY, key);
    input.value = "";
    showKeyState(0);
    loadAll();
    return;
  }
  const action = ACTIONS[attribute(form, "data-action")];
  if (!action) return; // a GET form: the browser navigates
  event.preventDefault();
  const outcome = find(form, ".outcome") || document.getElementById("predictions");
  const button = find(form, "button[type=submit]");
  button.disabled = true;
  Promise.resolve(action(form, outcome))
    .catch((error) => message(outcome, `Failed: ${error.message}`))
    .finally(() => { button.disabled = false; });
});

document.addEventListener("click", (event) => {
  const target = event.target.closest("button[data-post], a[data-download], #api-key-forget");
  if (!target) return;
  event.preventDefault();
  if (target.id === "api-key-forget") {
    sessionStorage.removeItem(KEY);
    showKeyState(0);
    loadAll();
  } else if (target.matches("button[data-post]")) {
    post(target);
  } else {
    download(target);
  }
});

document.addEventListener("change", (event) => {
  const form = event.target.form;
  if (form && attribute(form, "data-autosubmit") !== null) {
    HTMLFormElement.prototype.requestSubmit.call(form);
  }
});

document.addEventListener("DOMContentLoaded", () => {
  showKeyState(0);
  loadAll();
});
