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

// The service's words for a key it does not know (a key it knows but whose role is too low
// is refused with a message of its own, shown as it is).
const WRONG_KEY = "wrong API key";

async function errorOf(response) {
  try {
    return (await response.clone().json()).error || {};
  } catch (_) {
    return {};
  }
}

async function call(url, options = {}) {
  const sent = sessionStorage.getItem(KEY);
  const response = await fetch(url, { ...options, headers: apiHeaders(options.headers) });
  if (response.status === 401 && keyStill(sent)) showKeyState(401);
  if (response.status === 403) {
    // Reading the body yields: a new key may have been entered meanwhile, so ask after it.
    const wrong = (await errorOf(response)).message === WRONG_KEY;
    if (wrong && keyStill(sent)) showKeyState(403);
  }
  return response;
}

async function problem(response) {
  // One line from the JSON error body the service always answers.
  const error = await errorOf(response);
  if (!error.message) return `${response.status} ${response.statusText}`;
  const where = error.where ? ` (${error.where})` : "";
  if (response.status === 401) return "This service needs an API key: enter it at the top.";
  if (error.message === WRONG_KEY) return "The API key is wrong: enter the service's key at the top.";
  return `${error.message}${where}`;
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
  const go = region.querySelector("[data-go]");
  if (go) return location.assign(go.dataset.go); // a job made a page to see: open it
  const poll = region.querySelector("[data-poll]");
  if (poll) timers.set(region, setTimeout(() => load(region), Number(poll.dataset.poll)));
  fillTargets(region);
  region.querySelectorAll("form[data-action=upload-session]").forEach(showOptions);
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

// ------------------------------------------------------------------------------ requests

// A request's fields as the form holds them (inputs with data-field, their kind, default and
// the request's bounds in data- attributes): the values that differ from the defaults, and
// what breaks a bound, in the request's own field names.
function bounded(value, bounds, name, unit = "") {
  const limits = [
    ["minimum", (v, b) => v >= b, "greater than or equal to"],
    ["maximum", (v, b) => v <= b, "less than or equal to"],
    ["exclusiveminimum", (v, b) => v > b, "greater than"],
    ["exclusivemaximum", (v, b) => v < b, "less than"],
  ];
  for (const [key, holds, words] of limits) {
    if (bounds[key] !== undefined && !holds(value, Number(bounds[key]))) {
      return `${name}: Input should be ${words} ${bounds[key]}${unit}`;
    }
  }
  return null;
}

function readRequest(form) {
  const body = {};
  const errors = [];
  for (const input of findAll(form, "[data-field]")) {
    if (input.closest("[hidden]")) continue;
    input.removeAttribute("aria-invalid");
    const name = input.dataset.field;
    const kind = input.dataset.kind;
    const fail = (text) => errors.push([input, text]);
    if (kind === "boolean") {
      if (input.checked !== (input.dataset.default === "true")) body[name] = input.checked;
      continue;
    }
    const text = input.value.trim();
    if (text === "") {
      if (input.required) fail(`${name}: Field required`);
      continue;
    }
    if (text === input.dataset.default) continue;
    let value = text;
    if (kind === "integer" || kind === "number") {
      value = Number(text);
      if (!Number.isFinite(value)) { fail(`${name}: Input should be a finite number`); continue; }
      if (kind === "integer" && !Number.isInteger(value)) { fail(`${name}: Input should be a valid integer`); continue; }
      const wrong = bounded(value, input.dataset, name);
      if (wrong) { fail(wrong); continue; }
    } else if (kind === "list" || kind === "lines") {
      value = text.split(kind === "list" ? /[\s,]+/ : /\n/).map((v) => v.trim()).filter(Boolean);
      if (input.dataset.items === "number") {
        value = value.map(Number);
        if (value.some((v) => !Number.isFinite(v))) { fail(`${name}: Input should be a list of numbers`); continue; }
      }
      const items = { minimum: input.dataset.minitems, maximum: input.dataset.maxitems };
      const wrong = bounded(value.length, items, name, " items");
      if (wrong) { fail(wrong); continue; }
    } else {
      const wrong = bounded(text.length, { minimum: input.dataset.minlength, maximum: input.dataset.maxlength }, name, " characters");
      if (wrong) { fail(wrong); continue; }
    }
    body[name] = value;
  }
  return { body, errors };
}

// Mark the inputs a problem names (the page's own, or the service's `body.FIELD`).
function markInvalid(form, errors, outcome) {
  for (const [input] of errors) input.setAttribute("aria-invalid", "true");
  message(outcome, errors.map(([, text]) => text).join("; "));
  if (errors.length) errors[0][0].focus();
}

async function refused(form, response, outcome) {
  const error = await errorOf(response);
  const text = await problem(response);
  const field = (error.where || "").split(".")[1];
  const input = field ? find(form, `[data-field="${CSS.escape(field)}"]`) : null;
  // the request's field first, as the page's own checks say it (`race: needs ...`)
  const named = error.message && !error.message.startsWith("body.") ? `${field}: ${text}` : text;
  if (input) return markInvalid(form, [[input, named]], outcome);
  message(outcome, text);
}

async function sendRequest(form, outcome, url) {
  const { body, errors } = readRequest(form);
  if (errors.length) return markInvalid(form, errors, outcome);
  const response = await call(url, {
    method: "POST",
    headers: { "Content-Type": "application/json" },
    body: JSON.stringify(body),
  });
  if (!response.ok) {
    await refused(form, response, outcome);
    return null;
  }
  return response.json();
}

async function startRun(form, outcome) {
  const run = await sendRequest(form, outcome, "/api/runs");
  if (run) location.assign(`/runs/${run.id}`);
}

// A job's fragment, polled into `region` until the job ends.
function followJob(region, job) {
  region.dataset.src = `/fragments/jobs/${job}`;
  region.classList.add("region");
  load(region);
}

async function startJob(form, outcome) {
  const created = await sendRequest(form, outcome, attribute(form, "data-url"));
  if (!created) return;
  message(outcome, `Job ${created.job} ${created.status}.`, "ok");
  followJob(document.getElementById(attribute(form, "data-into")), created.job);
}

async function uploadSession(form, outcome) {
  const { body, errors } = readRequest(form);
  const files = find(form, "input[name=recordings]");
  if (!files.files.length) errors.push([files, "recordings: Field required"]);
  if (errors.length) return markInvalid(form, errors, outcome);
  const data = new FormData();
  for (const file of files.files) data.append("recordings", file);
  const labels = find(form, "input[name=labels]");
  if (labels.files.length) data.append("labels", labels.files[0]);
  for (const name of ["extractor", "events"]) {
    const value = find(form, `select[name=${name}]`).value;
    if (value) data.append(name, value);
  }
  for (const [name, value] of Object.entries(body)) {
    for (const item of Array.isArray(value) ? value : [value]) data.append(name, String(item));
  }
  const options = {};
  for (const input of findAll(form, "[data-option]")) {
    if (!input.closest("[hidden]") && input.value.trim() !== "") {
      options[input.dataset.option] = input.value.trim();
    }
  }
  if (Object.keys(options).length) data.append("options", JSON.stringify(options));
  const response = await call("/api/datasets/recordings", { method: "POST", body: data });
  if (!response.ok) return refused(form, response, outcome);
  const created = await response.json();
  message(outcome, `Extraction job ${created.job} ${created.status}: its progress below.`, "ok");
  followJob(document.getElementById("session-job"), created.job);
}

// Show the options of the extractor and the event detection chosen, and no others.
function showOptions(form) {
  const extractor = find(form, "select[name=extractor]");
  const events = find(form, "select[name=events]");
  if (!extractor || !events) return;
  const detector = events.value || extractor.selectedOptions[0].dataset.defaultEvents;
  for (const box of findAll(form, "[data-owner]")) {
    const owner = box.dataset.owner;
    box.hidden = owner !== `extractor:${extractor.value}` && owner !== `events:${detector}`;
  }
}

async function alias(form, outcome) {
  const model = attribute(form, "data-model");
  const created = await sendRequest(form, outcome, `/api/models/${encodeURIComponent(model)}/aliases`);
  if (created) loadAll();
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
  const options = { method: button.dataset.method || "POST" };
  if (button.dataset.body) {
    options.headers = { "Content-Type": "application/json" };
    options.body = button.dataset.body;
  }
  button.disabled = true;
  const response = await call(button.dataset.post, options);
  button.disabled = false;
  if (!response.ok) return message(outcome, await problem(response));
  if (button.dataset.into) {
    const created = await response.json();
    return followJob(document.getElementById(button.dataset.into), created.job);
  }
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
  "start-job": startJob,
  "upload-session": uploadSession,
  alias: alias,
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
  if (form && attribute(form, "data-action") === "upload-session") showOptions(form);
  if (form && attribute(form, "data-autosubmit") !== null) {
    HTMLFormElement.prototype.requestSubmit.call(form);
  }
});

document.addEventListener("DOMContentLoaded", () => {
  showKeyState(0);
  loadAll();
});
