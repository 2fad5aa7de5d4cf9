// fspec view: the page. Settings go to the server as JSON POSTs; frames
// come back as server-sent events (a PNG in base64 with its pass count).
"use strict";

const $ = (id) => document.getElementById(id);
const view = $("view");
let latest = null;        // the latest frame's metadata
let settings = null;      // the server's settings as last known

function showError(message) { $("error").textContent = message || ""; }

// Sends one change; the reply is the new generation or an error line.
async function post(patch) {
  const reply = await fetch("/api/settings", {
    method: "POST",
    headers: { "Content-Type": "application/json" },
    body: JSON.stringify(patch),
  });
  const body = await reply.json();
  if (!reply.ok) { showError(body.error); throw new Error(body.error); }
  showError("");
  return body;
}

// Camera moves: at most one request in flight, the latest move wins.
let cameraInFlight = false, cameraPending = null;
function sendCamera(camera) {
  cameraPending = camera;
  if (cameraInFlight) return;
  cameraInFlight = true;
  const next = cameraPending; cameraPending = null;
  post({ camera: next }).catch(() => {}).finally(() => {
    cameraInFlight = false;
    if (cameraPending) sendCamera(cameraPending);
  });
}

// Split view: the left half Fourier from the N, buffer and route controls,
// the right half sampled from the C and sampling controls.
function fourierOfControls() {
  return { kind: "fourier", coeffs: Number($("coeffs").value), buffer: $("buffer").value, to_color: $("to_color").value };
}
function sampledOfControls() {
  return { kind: "sampled", wavelengths: Number($("wavelengths").value), sampling: $("sampling").value };
}
function transportPatch() {
  if ($("split").checked) return { transport: fourierOfControls(), split: sampledOfControls() };
  return { transport: transportOfControls() };
}

function transportOfControls() {
  const kind = $("transport").value;
  const n = Number($("coeffs").value), c = Number($("wavelengths").value);
  const sampling = $("sampling").value;
  if (kind === "fourier") return { kind, coeffs: n, buffer: $("buffer").value, to_color: $("to_color").value };
  if (kind === "sampled") return { kind, wavelengths: c, sampling };
  if (kind === "hybrid") return { kind, coeffs: n, wavelengths: c, sampling, buffer: $("buffer").value, to_color: $("to_color").value };
  return { kind, wavelengths: c, coeffs: n, sampling, alpha_per_pixel: false };
}

function describeTransport(t) {
  if (t.kind === "fourier") return `Fourier N=${t.coeffs}`;
  if (t.kind === "sampled") return `sampled C=${t.wavelengths} ${t.sampling}`;
  return `cv C=${t.wavelengths} N=${t.coeffs}`;
}

function setControls(s) {
  settings = s;
  $("scene").value = s.scene;
  const t = s.transport;
  $("split").checked = !!s.split;
  $("transport").disabled = !!s.split;
  if (s.split) {
    $("wavelengths").value = String(s.split.wavelengths);
    $("sampling").value = s.split.sampling;
  }
  $("transport").value = t.kind;
  if (t.coeffs) $("coeffs").value = String(t.coeffs);
  if (t.wavelengths) $("wavelengths").value = String(t.wavelengths);
  if (t.sampling) $("sampling").value = t.sampling;
  if (t.buffer) $("buffer").value = t.buffer;
  if (t.to_color) $("to_color").value = t.to_color;
  $("exposure").value = String(s.exposure_stops);
  $("exposure-value").textContent = String(s.exposure_stops);
  $("tone").value = s.tone;
  $("illuminant").value = s.illuminant || "scene";
  $("observer").value = s.observer || "scene";
  $("max-passes").value = String(s.max_passes);
  if (![...$("size").options].some((o) => o.value === String(s.width) && s.width === s.height)) {
    const o = document.createElement("option");
    o.value = `${s.width}x${s.height}`; o.textContent = `${s.width} × ${s.height}`;
    $("size").appendChild(o); $("size").value = o.value;
  } else {
    $("size").value = String(s.width);
  }
}

function fill(select, names) {
  for (const name of names) {
    const o = document.createElement("option");
    o.value = name; o.textContent = name; select.appendChild(o);
  }
}

async function start() {
  const state = await (await fetch("/api/state")).json();
  fill($("scene"), state.scenes);
  fill($("illuminant"), ["scene"].concat(state.illuminants));
  fill($("observer"), ["scene"].concat(state.observers));
  setControls(state.settings);
  const onChange = (id, patch) => $(id).addEventListener("change", () => post(patch()).catch(() => {}));
  onChange("scene", () => ({ scene: $("scene").value }));
  onChange("size", () => {
    const [w, h] = $("size").value.split("x").map(Number);
    return { width: w, height: h || w };
  });
  for (const id of ["transport", "coeffs", "wavelengths", "sampling", "buffer", "to_color"]) {
    onChange(id, transportPatch);
  }
  onChange("split", () => ($("split").checked ? transportPatch() : { split_off: true }));
  onChange("observer", () => ({ observer: $("observer").value }));
  $("exposure").addEventListener("input", () => {
    $("exposure-value").textContent = $("exposure").value;
    post({ exposure_stops: Number($("exposure").value) }).catch(() => {});
  });
  onChange("tone", () => ({ tone: $("tone").value }));
  onChange("illuminant", () => ({ illuminant: $("illuminant").value }));
  onChange("max-passes", () => ({ max_passes: Number($("max-passes").value) }));
  $("reset-camera").addEventListener("click", () => post({ reset_camera: true }).catch(() => {}));

  const events = new EventSource("/api/events");
  events.addEventListener("frame", (e) => {
    const frame = JSON.parse(e.data);
    view.src = "data:image/png;base64," + frame.png;
    delete frame.png;
    latest = frame;
    view.dataset.generation = String(frame.generation);
    view.dataset.passes = String(frame.passes);
    view.dataset.complete = String(frame.split ? frame.split.done : frame.passes === frame.passes_total);
    $("split-labels").hidden = !frame.split;
    if (frame.split) {
      const half = (h) => `${describeTransport(h.transport)} · ${h.passes} spp · ${h.seconds.toFixed(2)} s`;
      $("split-left").textContent = "◧ left: " + half(frame.split.left);
      $("split-right").textContent = "◨ right: " + half(frame.split.right);
    }
    const seconds = frame.elapsed_ms / 1000;
    const rate = frame.passes / Math.max(seconds, 1e-9);
    $("status").textContent =
      `pass ${frame.passes}/${frame.passes_total} · ${seconds.toFixed(2)} s · ${rate.toFixed(1)} passes/s · ${frame.width}×${frame.height} · generation ${frame.generation}`;
    $("command").textContent = frame.render_command ? "same image: " + frame.render_command : "";
    if (!dragging) setControls(frame.settings);
  });
  events.addEventListener("error", (e) => {
    if (e.data) showError(JSON.parse(e.data).error);
  });
}

// --- camera: orbit about the scene's centre, pan, dolly ---
const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
const mul = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const norm = (a) => mul(a, 1 / Math.hypot(a[0], a[1], a[2]));
// Rodrigues: v rotated by `angle` about unit `axis`.
function rotate(v, axis, angle) {
  const c = Math.cos(angle), s = Math.sin(angle);
  return add(add(mul(v, c), mul(cross(axis, v), s)), mul(axis, dot(axis, v) * (1 - c)));
}

// Radians of orbit per pixel dragged.
const ORBIT_PER_PX = 0.01;
// Closest the orbit comes to the poles (cosine between view and up).
const POLE_COS = 0.99;

let dragging = null;
function cameraOf(frame) {
  const c = frame.camera;
  const target = add(c.position, mul(c.forward, c.pivot_distance));
  return { position: c.position, target, up: c.world_up, fov_deg: c.fov_deg, right: cross(c.forward, c.up), upv: c.up };
}

view.addEventListener("contextmenu", (e) => e.preventDefault());
view.addEventListener("mousedown", (e) => {
  if (!latest) return;
  dragging = { x: e.clientX, y: e.clientY, camera: cameraOf(latest), pan: e.shiftKey || e.button === 2, moved: false };
  e.preventDefault();
});
window.addEventListener("mousemove", (e) => {
  if (!dragging) return;
  const dx = e.clientX - dragging.x, dy = e.clientY - dragging.y;
  if (Math.abs(dx) + Math.abs(dy) < 3 && !dragging.moved) return;
  dragging.moved = true;
  const c = dragging.camera;
  if (dragging.pan) {
    // One screen pixel at the pivot's depth, in scene units.
    const shown = view.clientHeight || 1;
    const unit = 2 * Math.tan((c.fov_deg * Math.PI) / 360) * Math.hypot(...sub(c.target, c.position)) / shown;
    const shift = add(mul(c.right, -dx * unit), mul(c.upv, dy * unit));
    sendCamera({ position: add(c.position, shift), target: add(c.target, shift), up: c.up, fov_deg: c.fov_deg });
  } else {
    const up = norm(c.up);
    let offset = rotate(sub(c.position, c.target), up, -dx * ORBIT_PER_PX);
    const right = norm(cross(up, offset));
    const pitched = rotate(offset, right, -dy * ORBIT_PER_PX);
    if (Math.abs(dot(norm(pitched), up)) < POLE_COS) offset = pitched;
    sendCamera({ position: add(c.target, offset), target: c.target, up: c.up, fov_deg: c.fov_deg });
  }
});
window.addEventListener("mouseup", (e) => {
  const was = dragging;
  dragging = null;
  if (was && !was.moved && e.target === view) showSpectrum(e);
});
view.addEventListener("wheel", (e) => {
  if (!latest) return;
  e.preventDefault();
  const c = cameraOf(latest);
  // Dolly: the distance to the pivot scales by e^(wheel/500).
  const offset = mul(sub(c.position, c.target), Math.exp(e.deltaY / 500));
  sendCamera({ position: add(c.target, offset), target: c.target, up: c.up, fov_deg: c.fov_deg });
}, { passive: false });

// --- a pixel's spectrum ---
async function showSpectrum(e) {
  if (!latest) return;
  const r = view.getBoundingClientRect();
  const x = Math.floor(((e.clientX - r.left) / r.width) * latest.width);
  const y = Math.floor(((e.clientY - r.top) / r.height) * latest.height);
  $("spectrum-caption").textContent = `tracing pixel (${x}, ${y}) both ways…`;
  const reply = await fetch(`/api/spectrum?x=${x}&y=${y}`);
  const body = await reply.json();
  if (!reply.ok) { $("spectrum-caption").textContent = body.error; $("spectrum").innerHTML = ""; return; }
  plot(body);
}

// The Fourier curve as a line, the sampled estimate as a dot per bin with
// a bar of ±1 standard error.
function plot(s) {
  const W = 320, H = 180, L = 30, B = 20, T = 8, R = 8;
  const lo = s.lambda_nm[0], hi = s.lambda_nm[s.lambda_nm.length - 1];
  const b = s.sampled;
  const upper = b.radiance.map((v, i) => v + b.std_error[i]);
  const top = Math.max(...s.radiance, ...upper, 1e-12);
  const px = (l) => L + ((l - lo) / (hi - lo)) * (W - L - R);
  const py = (v) => H - B - (Math.max(v, 0) / top) * (H - B - T);
  const d = s.lambda_nm.map((l, i) => `${i ? "L" : "M"}${px(l).toFixed(1)},${py(s.radiance[i]).toFixed(1)}`).join("");
  let svg = `<line x1="${L}" y1="${H - B}" x2="${W - R}" y2="${H - B}"/><line x1="${L}" y1="${T}" x2="${L}" y2="${H - B}"/>`;
  for (let l = 400; l <= hi; l += 100) svg += `<text x="${px(l) - 10}" y="${H - 6}">${l}</text>`;
  svg += `<text x="2" y="${T + 8}">${top.toPrecision(2)}</text><path d="${d}"/>`;
  b.bin_centre_nm.forEach((l, i) => {
    const x = px(l).toFixed(1), v = b.radiance[i], e = b.std_error[i];
    svg += `<line class="bar" x1="${x}" x2="${x}" y1="${py(v - e).toFixed(1)}" y2="${py(v + e).toFixed(1)}"/>`;
    svg += `<circle cx="${x}" cy="${py(v).toFixed(1)}" r="1.6"/>`;
  });
  $("spectrum").innerHTML = svg;
  $("spectrum-caption").textContent =
    `pixel (${s.x}, ${s.y}): line, Fourier N=${s.coefficients.length} (${s.fourier_paths} paths); ` +
    `dots, sampled C=${b.wavelengths_per_path} ${b.sampling} per ${b.bin_width_nm.toFixed(0)} nm bin ` +
    `±1 s.e. (${b.paths} paths); ${lo}–${hi} nm`;
}

start().catch((e) => showError(String(e)));
