// spectrace view: the page of `spectrace view` and of the notebook's view. It shows the render as the server's
// event stream reports each pass and sends the controls' values as JSON; the server checks every value.
"use strict";

const token = new URLSearchParams(location.search).get("token") || "";
const $ = (id) => document.getElementById(id);
let state = null;
let shownVersion = -1;
let lightKeys = "";
let pixel = null;

function api(path, query) {
  const params = new URLSearchParams(query || {});
  params.set("token", token);
  return path + "?" + params.toString();
}

function showError(text) {
  $("error").textContent = text || "";
}

async function post(path, body) {
  try {
    const reply = await fetch(api(path), {
      method: "POST",
      headers: { "Content-Type": "application/json" },
      body: JSON.stringify(body),
    });
    const answer = await reply.json();
    showError(answer.error || "");
    return answer;
  } catch (failure) {
    showError("the viewer's server does not answer (" + failure + ")");
    return { error: String(failure) };
  }
}

function seconds(value) {
  if (value === null || value === undefined) return "–";
  return value < 60 ? value.toFixed(1) + " s" : (value / 60).toFixed(1) + " min";
}

function fillSelect(select, values, labels) {
  const wanted = values.join("\n");
  if (select.dataset.values === wanted) return;
  const chosen = select.value;
  select.replaceChildren(...values.map((value, i) => new Option(labels ? labels[i] : value, value)));
  select.dataset.values = wanted;
  if (values.includes(chosen)) select.value = chosen;
}

function showLights(lights) {
  const keys = Object.keys(lights);
  $("lights-box").hidden = keys.length === 0;
  if (keys.join("\n") === lightKeys) return;
  lightKeys = keys.join("\n");
  const rows = keys.map((key) => {
    const row = document.createElement("label");
    const on = document.createElement("input");
    on.type = "checkbox";
    on.checked = lights[key] > 0;
    on.dataset.key = key;
    const scale = document.createElement("input");
    scale.type = "number";
    scale.min = "0";
    scale.step = "any";
    scale.value = String(lights[key] > 0 ? lights[key] : 1);
    scale.dataset.key = key;
    const name = document.createElement("span");
    name.textContent = key;
    on.addEventListener("change", () => post("/api/update", { changes: { [key]: on.checked ? Number(scale.value) : 0 } }));
    scale.addEventListener("change", () => {
      on.checked = Number(scale.value) > 0;
      post("/api/update", { changes: { [key]: Number(scale.value) } });
    });
    row.append(on, scale, name);
    return row;
  });
  $("lights").replaceChildren(...rows);
}

function show(next) {
  state = next;
  const paused = state.paused ? " · paused" : "";
  const done = state.spp >= state.target_spp ? " · done" : "";
  $("status").textContent =
    `${state.spp}/${state.target_spp} spp · ${seconds(state.seconds)} · ETA ${seconds(state.eta)}${paused}${done}`;
  $("status").dataset.spp = String(state.spp);
  $("status").dataset.version = String(state.version);
  $("pause").textContent = state.paused ? "resume" : "pause";
  if (state.error) showError(state.error);
  fillSelect($("colour-space"), state.spaces);
  fillSelect($("observer"), state.observers);
  if (document.activeElement !== $("observer")) $("observer").value = state.observer;
  fillSelect($("channel"), ["", ...state.channels], ["film XYZ", ...state.channels]);
  $("colour-space").value = state.display.colour_space;
  $("channel").value = state.display.channel;
  $("false-colour").checked = state.display.false_colour;
  if (document.activeElement !== $("exposure")) {
    $("exposure").value = String(state.display.exposure);
    $("exposure-value").textContent = String(state.display.exposure);
  }
  if (document.activeElement !== $("white-balance")) $("white-balance").value = state.display.white_balance;
  showLights(state.lights);
  refreshImage();
}

function refreshImage() {
  if (!state || state.spp === 0) return;
  const key = state.version + ":" + JSON.stringify(state.display);
  if (key === shownVersion) return;
  shownVersion = key;
  $("image").src = api("/api/image.png", { v: key });
  $("image").dataset.spp = String(state.spp);
}

function connect() {
  const events = new EventSource(api("/api/events"));
  events.addEventListener("state", (event) => show(JSON.parse(event.data)));
  events.onerror = () => {
    $("status").textContent = "connection lost; retrying…";
  };
}

// ------------------------------------------------------------------ display controls

$("exposure").addEventListener("input", () => {
  $("exposure-value").textContent = $("exposure").value;
  post("/api/display", { exposure: Number($("exposure").value) });
});
$("colour-space").addEventListener("change", () => post("/api/display", { colour_space: $("colour-space").value }));
$("channel").addEventListener("change", () => post("/api/display", { channel: $("channel").value }));
$("false-colour").addEventListener("change", () => post("/api/display", { false_colour: $("false-colour").checked }));
$("white-balance").addEventListener("change", () => post("/api/display", { white_balance: $("white-balance").value }));
$("observer").addEventListener("change", () => post("/api/update", { changes: { "film.observer": $("observer").value } }));
$("pause").addEventListener("click", () => post("/api/pause", { paused: !(state && state.paused) }));

// ------------------------------------------------------------------ save

async function save(kind) {
  let name = $("save-name").value.trim();
  if (kind === "scene") name = name.replace(/\.(exr|png)$/i, "") + (name.toLowerCase().endsWith(".toml") ? "" : ".toml");
  const answer = await post("/api/save", { kind, name });
  $("saved").textContent = answer.saved ? "saved " + answer.saved : "";
}
$("save-image").addEventListener("click", () => save("image"));
$("save-scene").addEventListener("click", () => save("scene"));

// ------------------------------------------------------------------ camera: drag, shift-drag, wheel; click: pixel

const image = $("image");
let drag = null;
image.addEventListener("pointerdown", (event) => {
  drag = { x: event.clientX, y: event.clientY, pan: event.shiftKey || event.button === 2, moved: false };
  image.setPointerCapture(event.pointerId);
});
image.addEventListener("pointermove", (event) => {
  if (drag && Math.hypot(event.clientX - drag.x, event.clientY - drag.y) > 3) drag.moved = true;
});
image.addEventListener("pointerup", (event) => {
  if (!drag) return;
  const dx = event.clientX - drag.x;
  const dy = event.clientY - drag.y;
  const width = image.clientWidth || 1;
  if (drag.moved) {
    if (drag.pan) post("/api/camera", { action: "pan", dx: dx / width, dy: dy / width });
    else post("/api/camera", { action: "orbit", dx: (180 * dx) / width, dy: (180 * dy) / width });
  } else {
    const x = Math.floor((event.offsetX * image.naturalWidth) / width);
    const y = Math.floor((event.offsetY * image.naturalHeight) / (image.clientHeight || 1));
    pickPixel(x, y);
  }
  drag = null;
});
image.addEventListener("contextmenu", (event) => event.preventDefault());
let wheelTimer = null;
let wheelFactor = 1;
image.addEventListener(
  "wheel",
  (event) => {
    event.preventDefault();
    wheelFactor *= event.deltaY > 0 ? 1.1 : 1 / 1.1;
    clearTimeout(wheelTimer);
    wheelTimer = setTimeout(() => {
      post("/api/camera", { action: "zoom", dy: wheelFactor });
      wheelFactor = 1;
    }, 150);
  },
  { passive: false },
);

// ------------------------------------------------------------------ a pixel's spectrum

async function pickPixel(x, y) {
  try {
    const reply = await fetch(api("/api/pixel", { x, y, size: $("average").value }));
    const answer = await reply.json();
    if (answer.error) return showError(answer.error);
    pixel = answer;
    showPixel();
    $("reference").disabled = false;
  } catch (failure) {
    showError("the viewer's server does not answer (" + failure + ")");
  }
}

function number(value) {
  return Math.abs(value) >= 1e-3 && Math.abs(value) < 1e4 ? value.toPrecision(4) : value.toExponential(3);
}

function showPixel() {
  const p = pixel;
  const where = p.pixels > 1 ? `mean of ${p.pixels} pixels about (${p.x}, ${p.y})` : `pixel (${p.x}, ${p.y})`;
  const lines = [where, `XYZ ${p.xyz.map(number).join(" ")}`];
  lines.push(p.xy ? `xy ${p.xy.map((v) => v.toFixed(4)).join(" ")}` : "xy – (black)");
  if (p.delta_e !== undefined) lines.push(`ΔE2000 ${p.delta_e.toFixed(2)} to pixel (${p.reference.join(", ")})`);
  if (p.wavelengths_nm) {
    const peak = p.wavelengths_nm[p.radiance.indexOf(Math.max(...p.radiance))];
    lines.push(`peak ${peak.toFixed(0)} nm`);
    $("pixel-text").dataset.peak = String(peak);
  }
  $("pixel-text").textContent = lines.join("\n");
  drawSpectrum(p);
}

function drawSpectrum(p) {
  const canvas = $("spectrum");
  const g = canvas.getContext("2d");
  g.clearRect(0, 0, canvas.width, canvas.height);
  if (!p.wavelengths_nm) return;
  const w = p.wavelengths_nm;
  const left = 30, bottom = canvas.height - 20, width = canvas.width - 40, height = canvas.height - 30;
  const x = (nm) => left + ((nm - w[0]) / (w[w.length - 1] - w[0])) * width;
  const line = (values, colour, top) => {
    g.strokeStyle = colour;
    g.beginPath();
    values.forEach((v, i) => g.lineTo(x(w[i]), bottom - (top > 0 ? v / top : 0) * height));
    g.stroke();
  };
  const curves = p.observer.curves;
  const curveTop = Math.max(...curves.flat());
  ["#c33", "#3a3", "#33c"].forEach((colour, i) => {
    g.setLineDash([4, 3]);
    line(curves[i], colour, curveTop);
  });
  g.setLineDash([]);
  const error = p.radiance_error;
  const top = Math.max(...p.radiance.map((v, i) => v + (error ? error[i] : 0)));
  if (error) {
    // The mean ± one standard error, from the spread between the averaged pixels.
    const y = (v) => bottom - (top > 0 ? v / top : 0) * height;
    g.fillStyle = "rgba(0, 0, 0, 0.15)";
    g.beginPath();
    p.radiance.forEach((v, i) => g.lineTo(x(w[i]), y(v + error[i])));
    for (let i = w.length - 1; i >= 0; i--) g.lineTo(x(w[i]), y(Math.max(p.radiance[i] - error[i], 0)));
    g.closePath();
    g.fill();
  }
  g.lineWidth = 2;
  line(p.radiance, "#000", top);
  g.lineWidth = 1;
  g.fillStyle = "#000";
  g.font = "11px sans-serif";
  for (const nm of [400, 500, 600, 700, 800]) if (nm >= w[0] && nm <= w[w.length - 1]) g.fillText(String(nm), x(nm) - 10, canvas.height - 5);
  const band = error ? " ± standard error (grey)" : "";
  g.fillText("radiance (solid)" + band + ", " + p.observer.label + " (dashed)", left, 12);
}

$("average").addEventListener("change", () => {
  if (pixel) pickPixel(pixel.x, pixel.y);
});

$("reference").addEventListener("click", async () => {
  if (!pixel) return;
  const answer = await post("/api/reference", { x: pixel.x, y: pixel.y, size: Number($("average").value) });
  if (!answer.error) pickPixel(pixel.x, pixel.y);
});

fetch(api("/api/state"))
  .then((reply) => reply.json())
  .then(show)
  .catch((failure) => showError("the viewer's server does not answer (" + failure + ")"));
connect();
