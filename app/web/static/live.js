// touchbench's live view: opens the live WebSocket on a source the service reads itself
// (a simulated sensor, or a recording uploaded for replay), scrolls the signal on a canvas,
// marks each touch with its predicted labels, and shows when the champion switches.
// The API key comes from this tab's session storage, as for the rest of the page; the
// socket carries it in its first message (a browser cannot add a header to a handshake).
// Everything shown is built with textContent; nothing is fetched from another origin.
"use strict";

(() => {
  const KEY = "touchbench.apiKey";
  const WINDOW = 10; // seconds of signal on the canvas
  const COLOURS = ["#1f5f99", "#b3261e", "#1e7b34", "#9a6700", "#6a3d9a", "#00838f", "#ad1457"];
  const CHANNEL_COLOURS = ["#24303d", "#5b6570", "#8a96a3", "#3d5a80", "#7b6d8d", "#596e5a"];

  const $ = (id) => document.getElementById(id);
  const key = () => sessionStorage.getItem(KEY);
  const headers = () => (key() ? { "X-API-Key": key() } : {});
  const now = () => performance.timeOrigin + performance.now(); // ms since the epoch

  let socket = null;
  let view = null; // what the canvas draws: signal columns, touches, switches
  let drawing = false; // a frame is asked for: what arrived is drawn in it

  function say(text, kind = "note") {
    const status = $("live-status");
    status.className = `outcome ${kind}`;
    status.textContent = text;
  }

  async function problem(response) {
    if (response.status === 401) return "This service needs an API key: enter it at the top.";
    if (response.status === 403) return "The API key is wrong or may not do this.";
    try {
      const error = (await response.json()).error || {};
      return error.message || response.statusText;
    } catch (_) {
      return `${response.status} ${response.statusText}`;
    }
  }

  // ---------------------------------------------------------------------------- choices

  async function fillModels() {
    const list = $("live-models");
    let response;
    try {
      response = await fetch("/api/models?limit=1000", { headers: headers() });
    } catch (_) {
      return;
    }
    if (!response.ok) return;
    const names = new Set();
    list.replaceChildren();
    for (const model of (await response.json()).models) {
      const refs = [`${model.name}@${model.version}`];
      for (const alias of model.aliases) refs.unshift(`${model.name}@${alias}`);
      if (!names.has(model.name)) refs.unshift(model.name);
      names.add(model.name);
      for (const ref of refs) {
        const option = document.createElement("option");
        option.value = ref;
        list.append(option);
      }
    }
  }

  function addReplay(replay, chosen) {
    const select = $("live-replay");
    const option = document.createElement("option");
    option.value = replay.id;
    option.textContent = `${replay.name} (${replay.seconds.toFixed(1)} s, ` +
      `${replay.channels} ch, ${replay.samplerate} Hz)`;
    select.append(option);
    if (chosen) select.value = replay.id;
  }

  async function fillReplays() {
    let response;
    try {
      response = await fetch("/api/live/recordings", { headers: headers() });
    } catch (_) {
      return;
    }
    if (!response.ok) return;
    const select = $("live-replay");
    select.replaceChildren(select.options[0]);
    for (const replay of (await response.json()).replays) addReplay(replay, false);
  }

  async function upload(input) {
    const file = input.files[0];
    if (!file) return;
    const body = new FormData();
    body.append("recording", file, file.name);
    say(`Uploading ${file.name}…`);
    const response = await fetch("/api/live/recordings", {
      method: "POST", body, headers: headers(),
    });
    if (!response.ok) return say(await problem(response), "error");
    const replay = await response.json();
    addReplay(replay, true);
    input.value = "";
    say(`Uploaded ${replay.name}: ${replay.seconds.toFixed(1)} s to replay.`, "ok");
  }

  function showSourceFields() {
    const kind = $("live-form").querySelector("input[name=kind]:checked").value;
    for (const label of document.querySelectorAll("#live-form label[data-for]")) {
      label.hidden = label.dataset.for !== kind;
    }
  }

  // ---------------------------------------------------------------------------- session

  function sourceOf(form) {
    const data = new FormData(form);
    const source = { kind: data.get("kind"), speed: Number(data.get("speed")) };
    if (source.kind === "replay") {
      if (!data.get("replay")) throw new Error("Upload a recording or pick one to replay.");
      source.replay = data.get("replay");
    } else {
      source.touches = Number(data.get("touches"));
      source.seed = Number(data.get("seed"));
    }
    return source;
  }

  function start(form) {
    const model = String(new FormData(form).get("model")).trim();
    if (!model) return say("Name a model (NAME, NAME@champion or NAME@3).", "error");
    let source;
    try {
      source = sourceOf(form);
    } catch (error) {
      return say(error.message, "error");
    }
    stop();
    reset();
    const scheme = location.protocol === "https:" ? "wss" : "ws";
    const url = `${scheme}://${location.host}/api/models/${encodeURIComponent(model)}/live`;
    const opened = new WebSocket(url);
    socket = opened;
    setRunning(true, "connecting");
    say(`Opening ${model}…`);
    opened.onopen = () => {
      const header = { source };
      if (key()) header.api_key = key();
      opened.send(JSON.stringify(header));
    };
    opened.onmessage = (event) => {
      if (socket === opened) receive(JSON.parse(event.data));
    };
    opened.onclose = (event) => {
      if (socket !== opened) return;
      socket = null;
      closed(event);
    };
  }

  function stop() {
    if (socket && socket.readyState === WebSocket.OPEN) {
      socket.send(JSON.stringify({ end: true }));
    } else if (socket) {
      socket.close();
    }
  }

  function setRunning(running, state) {
    $("live-start").disabled = running;
    $("live-stop").disabled = !running;
    $("live-touches").dataset.state = state;
  }

  function closed(event) {
    const count = view.touches.length;
    const touches = `${count} touch${count === 1 ? "" : "es"}`;
    if (event.code === 1000) {
      const why = event.reason === "source ended" ? "The source ended" : "Stopped";
      say(`${why}: ${touches} marked.`, "ok");
      setRunning(false, "ended");
    } else {
      const reason = event.reason || "the connection was refused or lost";
      say(`The live session closed (${event.code}): ${reason}`, "error");
      setRunning(false, "closed");
    }
  }

  function reset() {
    view = { columns: [], channels: 0, end: 0, touches: [], switches: [], models: new Map() };
    $("live-touches").tBodies[0].replaceChildren();
    $("live-last").replaceChildren();
    $("live-switch").hidden = true;
    $("live-source").textContent = "";
    redraw();
  }

  function receive(message) {
    if (message.signal) return addSignal(message.signal);
    if (message.source) return started(message.source);
    if (message.switched) return switched(message);
    if (message.warning) return say(message.warning, "error");
    if (message.predictions) return addTouch(message);
  }

  function started(source) {
    view.channels = source.channels;
    view.model = source.model;
    const speed = source.speed === 1 ? "real time" : `${source.speed}× real time`;
    $("live-source").textContent = `${source.model} on ${source.name}: ${source.channels} ` +
      `channel(s) at ${source.samplerate} Hz, ${speed}`;
    setRunning(true, "running");
    say("Listening…");
    redraw();
  }

  function addSignal(signal) {
    const count = signal.peaks[0].length;
    for (let i = 0; i < count; i += 1) {
      view.columns.push({ t: signal.time + i * signal.step, peaks: signal.peaks.map((c) => c[i]) });
    }
    view.step = signal.step;
    view.end = signal.time + count * signal.step;
    while (view.columns.length && view.columns[0].t < view.end - WINDOW) view.columns.shift();
    redraw();
  }

  function switched(message) {
    const line = $("live-source");
    line.textContent = line.textContent.replace(message.from, message.switched);
    view.switches.push({ t: view.end, from: message.from, to: message.switched });
    const banner = $("live-switch");
    banner.hidden = false;
    banner.textContent = `Champion switched at ${view.end.toFixed(2)} s: ` +
      `${message.from} → ${message.switched}`;
    const row = document.createElement("tr");
    row.className = "switch";
    const cell = document.createElement("td");
    cell.colSpan = 6;
    cell.textContent = `switched from ${message.from} to ${message.switched}`;
    row.append(cell);
    $("live-touches").tBodies[0].prepend(row);
    redraw();
  }

  function colour(label) {
    if (!view.models.has(label)) view.models.set(label, COLOURS[view.models.size % COLOURS.length]);
    return view.models.get(label);
  }

  function labelsOf(touch) {
    return Object.entries(touch.predictions).map(([target, p]) => {
      const value = typeof p.value === "number" ? p.value.toFixed(3) : String(p.value);
      const chance = typeof p.probability === "number" ? ` (${p.probability.toFixed(2)})` : "";
      return { target, value, text: `${target}: ${value}${chance}`, probability: p.probability };
    });
  }

  function cell(row, text, className = "") {
    const element = document.createElement("td");
    element.textContent = text;
    if (className) element.className = className;
    row.append(element);
    return element;
  }

  function addTouch(touch) {
    const labels = labelsOf(touch);
    const mark = { ...touch, labels, colour: colour(labels.map((l) => l.value).join(" · ")) };
    view.touches.push(mark);
    const row = document.createElement("tr");
    row.className = "touch";
    row.dataset.start = touch.start;
    row.dataset.end = touch.end;
    row.dataset.model = touch.model;
    row.dataset.latencyMs = touch.latency_ms;
    row.dataset.labels = JSON.stringify(Object.fromEntries(labels.map((l) => [l.target, l.value])));
    cell(row, String(view.touches.length), "num");
    cell(row, `${touch.start.toFixed(2)}–${touch.end.toFixed(2)}`, "num");
    const named = cell(row, labels.map((l) => l.text).join(" · "));
    named.style.borderLeftColor = mark.colour; // a CSSOM property, allowed by the policy
    named.classList.add("labels");
    cell(row, touch.model);
    cell(row, touch.latency_ms.toFixed(1), "num");
    const shown = cell(row, "…", "num delay");
    $("live-touches").tBodies[0].prepend(row);
    showLast(mark);
    redraw();
    // The frame that draws the mark: how long after the touch's end (on the service's
    // clock, the same as this machine's on loopback) the page showed it.
    requestAnimationFrame(() => {
      if (typeof touch.ended_at !== "number") return;
      const delay = now() - touch.ended_at * 1000;
      row.dataset.delayMs = delay.toFixed(1);
      shown.textContent = delay.toFixed(1);
    });
  }

  function showLast(mark) {
    const box = $("live-last");
    box.replaceChildren();
    const heading = document.createElement("p");
    heading.className = "live-last-time";
    heading.textContent = `Touch ${view.touches.length} at ${mark.start.toFixed(2)} s`;
    box.append(heading);
    for (const label of mark.labels) {
      const line = document.createElement("p");
      line.className = "live-label";
      const name = document.createElement("span");
      name.className = "live-target";
      name.textContent = label.target;
      const value = document.createElement("strong");
      value.textContent = label.value;
      line.append(name, value);
      if (typeof label.probability === "number") {
        const bar = document.createElement("meter");
        bar.min = 0;
        bar.max = 1;
        bar.value = label.probability;
        bar.title = `probability ${label.probability.toFixed(2)}`;
        const figure = document.createElement("span");
        figure.className = "live-probability";
        figure.textContent = label.probability.toFixed(2);
        line.append(bar, figure);
      }
      box.append(line);
    }
    const by = document.createElement("p");
    by.className = "note";
    by.textContent = `by ${mark.model}, ${mark.latency_ms.toFixed(1)} ms after its end`;
    box.append(by);
  }

  // ---------------------------------------------------------------------------- canvas

  // Drawn in the next animation frame after something arrived, not every frame: the
  // signal comes 20 times a second, and a projector's laptop has other work to do.
  function redraw() {
    if (drawing) return;
    drawing = true;
    requestAnimationFrame(() => {
      drawing = false;
      draw();
    });
  }

  function draw() {
    const canvas = $("live-signal");
    const ratio = window.devicePixelRatio || 1;
    const width = canvas.clientWidth;
    const height = canvas.clientHeight;
    if (canvas.width !== Math.round(width * ratio)) canvas.width = Math.round(width * ratio);
    if (canvas.height !== Math.round(height * ratio)) canvas.height = Math.round(height * ratio);
    const g = canvas.getContext("2d");
    g.setTransform(ratio, 0, 0, ratio, 0, 0);
    g.clearRect(0, 0, width, height);
    const left = Math.max(0, view.end - WINDOW);
    const x = (t) => ((t - left) / WINDOW) * width;
    const top = 34; // room for the labels above the signal
    const lanes = Math.max(1, view.channels);
    const lane = (height - top - 18) / lanes;

    g.font = "15px system-ui, sans-serif";
    g.textBaseline = "top";
    for (const touch of view.touches) {
      if (touch.end < left) continue;
      g.fillStyle = touch.colour;
      g.globalAlpha = 0.16;
      g.fillRect(x(touch.start), top, Math.max(2, x(touch.end) - x(touch.start)), height - top - 18);
      g.globalAlpha = 1;
      g.fillRect(x(touch.start), top - 4, Math.max(2, x(touch.end) - x(touch.start)), 4);
      g.font = "bold 16px system-ui, sans-serif";
      g.fillText(touch.labels.map((l) => l.value).join(" · "), x(touch.start) + 2, 4);
      g.font = "15px system-ui, sans-serif";
    }
    for (let c = 0; c < lanes; c += 1) {
      const middle = top + lane * (c + 0.5);
      g.strokeStyle = CHANNEL_COLOURS[c % CHANNEL_COLOURS.length];
      g.lineWidth = 1.5;
      g.beginPath();
      for (const column of view.columns) {
        const peak = Math.min(1, (column.peaks[c] || 0) * 2.5) * (lane / 2 - 2);
        const at = x(column.t);
        g.moveTo(at, middle - peak);
        g.lineTo(at, middle + peak + 0.5);
      }
      g.stroke();
    }
    g.strokeStyle = "#9a6700";
    g.fillStyle = "#9a6700";
    g.lineWidth = 2;
    for (const change of view.switches) {
      if (change.t < left) continue;
      g.setLineDash([6, 4]);
      g.beginPath();
      g.moveTo(x(change.t), top);
      g.lineTo(x(change.t), height - 18);
      g.stroke();
      g.setLineDash([]);
      g.fillText(`→ ${change.to}`, x(change.t) + 4, height - 34);
    }
    g.fillStyle = "#5b6570";
    g.textBaseline = "bottom";
    for (let t = Math.ceil(left); t <= view.end; t += 1) g.fillText(`${t} s`, x(t) + 2, height);
  }

  // ---------------------------------------------------------------------------- wiring

  document.addEventListener("DOMContentLoaded", () => {
    const form = $("live-form");
    reset();
    const wanted = new URLSearchParams(location.search).get("model");
    if (wanted) $("live-model").value = wanted;
    showSourceFields();
    fillModels();
    fillReplays();
    form.addEventListener("submit", (event) => {
      event.preventDefault();
      start(form);
    });
    form.addEventListener("change", (event) => {
      if (event.target.name === "kind") showSourceFields();
      if (event.target.name === "recording") {
        upload(event.target).catch((error) => say(`Upload failed: ${error.message}`, "error"));
      }
    });
    $("live-stop").addEventListener("click", stop);
    // A key entered at the top: the lists may now be readable.
    $("api-key").addEventListener("submit", () => setTimeout(() => {
      fillModels();
      fillReplays();
    }));
  });
})();
