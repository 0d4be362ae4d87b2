import {localFrame, pixelDirection} from "./geometry.js";

// The viewer's controls: the page state (from the URL, then from the panel, the mouse and the
// keys), the status line, the progress bar and error messages.

const DEG = Math.PI / 180;
// Page state: name -> [default, low, high] for the numbers a URL or the panel may set
const NUMBERS = {
  width: [0, 0, 8192], height: [0, 0, 8192],
  fov: [60, 1, 170], fisheye_fov: [180, 10, 360],
  heading: [180, -1e6, 1e6], pitch: [10, -90, 90], roll: [0, -180, 180],
  altitude_m: [2, 0, 1e9], lat: [45, -90, 90], lon: [0, -180, 180],
  site_lat: [45, -90, 90], site_lon: [0, -180, 180],
  sun_zenith: [60, 0, 180], sun_azimuth: [180, -1e6, 1e6],
  compensation: [0, -10, 10],  // and ev100, within what the meter can choose (readUrlState)
  // clouds: the cover of every layer (-1: as configured), a factor on the winds, the clouds'
  // time without a date [s] (api.render's cloud_time_s: years 1-9999 from J2000 at most)
  cloud_coverage: [-1, 0, 1], wind: [1, 0, 10], cloud_time: [0, -1e11, 1e11],
};
const CHOICES = {projection: ["perspective", "fisheye"], operator: ["aces", "clamp", "exponential", "reinhard"],
                 quality: ["full", "preview"], mode: ["ground", "orbit"]};

export function showError(message) {
  const box = document.getElementById("error");
  box.textContent = message;
  box.hidden = !message;
}

export function showStatus(message) {
  document.getElementById("status").textContent = message;
}

export function showProgress(progress) {
  const bar = document.getElementById("progress");
  bar.hidden = !progress.busy;
  if (progress.busy) {
    bar.max = Math.max(progress.total, 1);
    bar.value = progress.done;
    document.getElementById("progress-label").textContent = `computing tables: ${progress.label} ${progress.stage}`;
  } else {
    document.getElementById("progress-label").textContent = "";
  }
}

// The state from the URL's query, checked; a bad value is named in the page and left at its default
export function readUrlState(description, layout) {
  const query = new URLSearchParams(window.location.search);
  const numbers = {...NUMBERS, ev100: [12, ...layout.exposure.ev100_range]};
  const state = {atmosphere: description.default, clouds: description.clouds.default,
                 amounts: {}, albedo: null, auto_exposure: true,
                 controls: true, projection: "perspective", operator: "aces", quality: "full",
                 mode: "ground", time: ""};
  for (const [name, [value]] of Object.entries(numbers)) state[name] = value;
  const problems = [];
  for (const [key, text] of query) {
    if (key in numbers) {
      const [, low, high] = numbers[key];
      const value = Number(text);
      if (text.trim() === "" || !Number.isFinite(value) || value < low || value > high) {
        problems.push(`${key} = ${text} must be a number in [${low}, ${high}]`);
      } else {
        state[key] = value;
        if (key === "ev100") state.auto_exposure = false;
      }
    } else if (key in CHOICES) {
      if (CHOICES[key].includes(text)) state[key] = text;
      else problems.push(`${key} = ${text}: choose one of ${CHOICES[key].join(", ")}`);
    } else if (key === "atmosphere") {
      if (description.atmospheres.some((a) => a.name === text)) state.atmosphere = text;
      else problems.push(`unknown atmosphere ${text}`);
    } else if (key === "clouds") {
      if (text === description.clouds.none || description.clouds.clouds.some((c) => c.name === text)) state.clouds = text;
      else problems.push(`unknown clouds ${text}: choose one of ${[description.clouds.none, ...description.clouds.clouds.map((c) => c.name)].join(", ")}`);
    } else if (key === "albedo" || key.startsWith("amount_")) {
      const value = Number(text);
      if (!Number.isFinite(value)) problems.push(`${key} = ${text} is not a number`);
      else if (key === "albedo") state.albedo = value;
      else state.amounts[key.slice(7)] = value;  // the server checks the range and the name
    } else if (key === "controls") {
      state.controls = text !== "0";
    } else if (key === "time") {
      state.time = text;
    } else if (key !== "token") {  // the token is api.js's
      problems.push(`unknown parameter ${key}`);
    }
  }
  if (!query.has("site_lat")) state.site_lat = state.lat;
  if (!query.has("site_lon")) state.site_lon = state.lon;
  if (problems.length) showError(`Ignored in the address: ${problems.join("; ")}`);
  return state;
}

function atmosphereOf(description, name) {
  return description.atmospheres.find((a) => a.name === name);
}

function slider(container, label, min, max, step, value, onInput) {
  const row = document.createElement("label");
  row.className = "row";
  const text = document.createElement("span");
  const input = document.createElement("input");
  Object.assign(input, {type: "range", min, max, step, value});
  const show = () => { text.textContent = `${label} ${Number(input.value).toFixed(2)}`; };
  input.addEventListener("input", () => { show(); onInput(Number(input.value)); });
  show();
  row.append(text, input);
  container.append(row);
  return input;
}

// Puts the sun along the local direction `dir` of the camera: zenith and azimuth at the site
function placeSun(state, dir) {
  const camera = localFrame(state.lat * DEG, state.lon * DEG);
  const world = [0, 1, 2].map((i) => camera[0][i] * dir[0] + camera[1][i] * dir[1] + camera[2][i] * dir[2]);
  const site = localFrame(state.site_lat * DEG, state.site_lon * DEG);
  const [e, n, u] = site.map((axis) => axis.reduce((sum, v, i) => sum + v * world[i], 0));
  state.sun_zenith = Math.acos(Math.max(-1, Math.min(1, u))) / DEG;
  state.sun_azimuth = (Math.atan2(e, n) / DEG + 360) % 360;
}

// Binds the panel (unless controls=0), the mouse, the keys and the automatic exposure; returns a
// function that shows a state changed elsewhere. Without the panel the view still follows the
// mouse, the keys and the meter (kiosk and dome use).
export function bindControls(viewer, description, reload, sky, reloadClouds, physicalChanged) {
  const state = viewer.state;
  document.getElementById("panel").hidden = !state.controls;
  const refresh = state.controls ? bindPanel(viewer, description, reload, sky, reloadClouds, physicalChanged)
                                 : () => {};
  bindPointer(viewer, refresh);
  let frames = 0;
  setInterval(() => {
    if (state.auto_exposure && viewer.model && frames++ % 2 === 0) {
      const metered = viewer.meter();
      if (metered !== null) state.ev100 = metered;
    }
    refresh();
  }, 250);
  return refresh;
}

// The panel's widgets; returns a function that shows the state in them
function bindPanel(viewer, description, reload, sky, reloadClouds, physicalChanged) {
  const state = viewer.state;
  const byId = (id) => document.getElementById(id);
  // Atmosphere
  const select = byId("atmosphere");
  for (const entry of description.atmospheres) {
    const option = new Option(`${entry.name}`, entry.name);
    option.title = entry.description;
    select.append(option);
  }
  select.value = state.atmosphere;
  const physical = byId("physical");
  const changed = physicalChanged;  // the fast model at once, the tables after a pause
  const buildPhysical = () => {
    physical.replaceChildren();
    const entry = atmosphereOf(description, state.atmosphere);
    for (const name of entry.constituents) {
      if (!(name in state.amounts)) state.amounts[name] = 1;
      slider(physical, `${name} ×`, 0, Math.min(description.max_amount, 10), 0.05, state.amounts[name],
             (value) => { state.amounts[name] = value; changed(); });
    }
    slider(physical, "ground albedo", 0, 1, 0.01, state.albedo ?? entry.albedo,
           (value) => { state.albedo = value; changed(); });
  };
  select.addEventListener("change", () => {
    state.atmosphere = select.value;
    state.amounts = {};
    state.albedo = null;
    buildPhysical();
    reload();
    reloadClouds();  // the planet's radius and star
  });
  buildPhysical();
  byId("quality").value = state.quality;
  byId("quality").addEventListener("change", (event) => { state.quality = event.target.value; reload(); });
  // Clouds: preset or the --clouds file, cover, wind, time (a date sets the time instead)
  const cloudSelect = byId("clouds");
  cloudSelect.append(new Option("none", description.clouds.none));
  for (const entry of description.clouds.clouds) {
    const option = new Option(entry.name, entry.name);
    option.title = entry.description;
    cloudSelect.append(option);
  }
  cloudSelect.value = state.clouds;
  cloudSelect.addEventListener("change", () => { state.clouds = cloudSelect.value; reloadClouds(); });
  const coverage = byId("cloud-coverage");
  const configured = byId("cloud-coverage-configured");
  configured.checked = state.cloud_coverage < 0;
  coverage.value = Math.max(state.cloud_coverage, 0);
  coverage.addEventListener("input", () => { state.cloud_coverage = Number(coverage.value); configured.checked = false; });
  configured.addEventListener("change", () => { state.cloud_coverage = configured.checked ? -1 : Number(coverage.value); });
  byId("wind").value = state.wind;
  byId("wind").addEventListener("input", (event) => { state.wind = Number(event.target.value); });
  const cloudTime = byId("cloud-time");
  cloudTime.value = state.cloud_time;
  cloudTime.addEventListener("input", () => { state.cloud_time = Number(cloudTime.value); });
  // Sun
  const sunElevation = byId("sun-elevation");
  const sunAzimuth = byId("sun-azimuth");
  const showSun = () => {
    sunElevation.value = 90 - state.sun_zenith;
    sunAzimuth.value = ((state.sun_azimuth % 360) + 360) % 360;
    byId("sun-readout").textContent = `sun elevation ${(90 - state.sun_zenith).toFixed(2)}°, azimuth ${sunAzimuth.value}°`;
  };
  sunElevation.addEventListener("input", () => { state.sun_zenith = 90 - Number(sunElevation.value); showSun(); });
  sunAzimuth.addEventListener("input", () => { state.sun_azimuth = Number(sunAzimuth.value); showSun(); });
  const time = byId("time");
  time.value = state.time || new Date().toISOString().slice(0, 16) + "Z";
  byId("site-lat").value = state.site_lat;
  byId("site-lon").value = state.site_lon;
  const sunFromDate = async () => {
    try {
      await sky(time.value, byId("site-lat").value, byId("site-lon").value);
    } catch (error) {
      showError(error.message);
      return false;
    }
    showError("");
    showSun();
    return true;
  };
  byId("sun-from-date").addEventListener("click", sunFromDate);
  let playing = null;
  byId("play").addEventListener("click", () => {
    if (playing) { clearInterval(playing); playing = null; byId("play").textContent = "play day"; return; }
    byId("play").textContent = "stop";
    playing = setInterval(async () => {
      const t = new Date(Date.parse(time.value) + Number(byId("rate").value) * 60000 / 10);
      time.value = t.toISOString().slice(0, 16) + "Z";
      if (!(await sunFromDate())) { clearInterval(playing); playing = null; byId("play").textContent = "play day"; }
    }, 100);
  });
  // Camera
  const altitude = byId("altitude");
  const showAltitude = () => {
    altitude.value = Math.log10(Math.max(state.altitude_m, 1));
    const km = state.altitude_m / 1000;
    byId("altitude-readout").textContent = km < 1 ? `${state.altitude_m.toFixed(0)} m` : `${km.toFixed(km < 100 ? 1 : 0)} km`;
  };
  altitude.addEventListener("input", () => { state.altitude_m = Math.pow(10, Number(altitude.value)); showAltitude(); });
  byId("projection").value = state.projection;
  byId("projection").addEventListener("change", (event) => { state.projection = event.target.value; });
  byId("mode").value = state.mode;
  byId("mode").addEventListener("change", (event) => {
    state.mode = event.target.value;
    if (state.mode === "orbit") {
      state.altitude_m = Math.max(state.altitude_m, 3 * description.atmospheres[0].radius_m);
      state.pitch = -90;
      state.projection = "perspective";
      byId("projection").value = "perspective";
      state.fov = 40;
    } else {
      state.lat = state.site_lat; state.lon = state.site_lon;
      state.altitude_m = 2; state.pitch = 10;
    }
    showAltitude();
  });
  const fov = byId("fov");
  fov.addEventListener("input", () => { state.fov = Number(fov.value); });
  // Exposure: the slider spans what the meter can choose (layout.exposure.ev100_range)
  const ev = byId("ev100");
  [ev.min, ev.max] = viewer.layout.exposure.ev100_range;
  const auto = byId("auto-exposure");
  auto.checked = state.auto_exposure;
  ev.addEventListener("input", () => { state.ev100 = Number(ev.value); auto.checked = false; state.auto_exposure = false; });
  auto.addEventListener("change", () => { state.auto_exposure = auto.checked; });
  byId("compensation").value = state.compensation;
  byId("compensation").addEventListener("input", (event) => { state.compensation = Number(event.target.value); });
  byId("operator").value = state.operator;
  byId("operator").addEventListener("change", (event) => { state.operator = event.target.value; });
  const show = () => {
    showSun();
    showAltitude();
    fov.value = state.fov;
    ev.value = state.ev100;
    byId("ev-readout").textContent = state.ev100.toFixed(2);
    byId("cloud-readout").textContent = state.clouds === description.clouds.none ? "" :
      `cover ${state.cloud_coverage < 0 ? "as configured" : state.cloud_coverage.toFixed(2)}, wind ×${state.wind.toFixed(2)}, ` +
      `time ${viewer.cloudTime().toFixed(0)} s${state.time ? " (the date's, since 2000-01-01 12:00 UTC)" : ""}`;
    const times = viewer.frameTimes;
    const gpu = viewer.gpuMs === null ? "" : `GPU ${viewer.gpuMs.toFixed(2)} ms per frame; `;
    const ms = times.length ? times.reduce((a, b) => a + b, 0) / times.length : null;
    const rate = ms === null ? "redraws when the view changes" : `${ms.toFixed(1)} ms between frames (${(1000 / ms).toFixed(0)} fps)`;
    byId("frame-time").textContent = `${gpu}${rate}; ${viewer.canvas.width}×${viewer.canvas.height}`;
  };
  show();
  return show;
}

// Mouse and keys: drag to look (ground) or to orbit; shift-drag or double-click places the sun;
// the wheel zooms (ctrl or orbit: altitude); Page Up/Down, E/Q climb and descend
function bindPointer(viewer, refresh) {
  const state = viewer.state;
  const canvas = viewer.canvas;
  let drag = null;
  canvas.addEventListener("pointerdown", (event) => {
    drag = {x: event.clientX, y: event.clientY};
    canvas.setPointerCapture(event.pointerId);
    if (event.shiftKey) placeSun(state, pixelDirection(state, canvas, event.offsetX, event.offsetY));
  });
  canvas.addEventListener("pointermove", (event) => {
    if (!drag) return;
    if (event.shiftKey) {
      placeSun(state, pixelDirection(state, canvas, event.offsetX, event.offsetY));
      refresh();
      return;
    }
    const scale = (state.projection === "perspective" ? state.fov : state.fisheye_fov) / canvas.clientHeight;
    const [dx, dy] = [event.clientX - drag.x, event.clientY - drag.y];
    drag = {x: event.clientX, y: event.clientY};
    if (state.mode === "orbit") {
      state.lat = Math.max(-89.9, Math.min(89.9, state.lat + dy * scale));
      state.lon = ((state.lon - dx * scale + 540) % 360) - 180;
    } else {
      state.heading = (state.heading - dx * scale + 360) % 360;
      state.pitch = Math.max(-90, Math.min(90, state.pitch + dy * scale));
    }
  });
  canvas.addEventListener("pointerup", () => { drag = null; });
  canvas.addEventListener("dblclick", (event) => {
    placeSun(state, pixelDirection(state, canvas, event.offsetX, event.offsetY));
    refresh();
  });
  canvas.addEventListener("wheel", (event) => {
    event.preventDefault();
    if (event.ctrlKey || state.mode === "orbit") {
      state.altitude_m = Math.min(1e9, Math.max(0, state.altitude_m * Math.exp(event.deltaY * 0.002) + (event.deltaY > 0 ? 1 : 0)));
    } else {
      state.fov = Math.max(1, Math.min(170, state.fov * Math.exp(event.deltaY * 0.001)));
    }
    refresh();
  }, {passive: false});
  window.addEventListener("keydown", (event) => {
    if (event.target.tagName === "INPUT") return;
    const factor = {PageUp: 1.5, e: 1.5, PageDown: 1 / 1.5, q: 1 / 1.5}[event.key];
    if (factor) {
      state.altitude_m = Math.max(0, state.altitude_m * factor + (factor > 1 ? 1 : 0));
      refresh();
    }
  });
}
