// The skyscatter viewer: ray-casts the precomputed tables in a WebGL2 fragment shader every
// frame (shaders/*.glsl, the GLSL twins of the Python renderer), asks the server for new
// tables when a physical parameter changes (a preview first, then the full tables), and
// places the sun by hand or from a date, time and place; clouds (shaders/clouds.glsl) from the
// server's cloud message, moved by their wind over the clouds' time. Until the tables for the
// current physical parameters arrive, the clear sky is drawn by the fast model (fast.js,
// shaders/fast_model.glsl), made again in the browser at each change.
import {apiFetch, apiJson} from "./api.js";
import {FastModel} from "./fast.js";
import {decodeClouds, decodeFast, decodeTables, deleteClouds, deleteTables, fetchLayout,
        uploadClouds, uploadTables} from "./tables.js";
import {bindControls, readUrlState, showError, showProgress, showStatus} from "./controls.js";
import {cameraBasis, coarseSpacing, dot, localFrame, mapFrame, pixelDirection, shadedStretch,
        sunDirection, toWorld} from "./geometry.js";

const LIBRARY = ["generated/constants.glsl", "shaders/parameterisation.glsl", "shaders/camera.glsl",
                 "shaders/sky.glsl", "shaders/tonemap.glsl"];
const CLOUDY = [...LIBRARY, "shaders/clouds.glsl"];
const SKY = [...CLOUDY, "shaders/main.frag"];
// Programs: [vertex sources, fragment sources, defines] (files under static/; "" = the
// full-screen triangle); the sky without clouds is a program of its own (main.frag), the
// clouds are drawn in passes (drawRefinedClouds), or marched in one without float targets
const PROGRAMS = {
  sky: [[""], SKY],
  cloudy_sky: [[""], SKY, "#define CLOUDS\n"],
  cloud_final: [[""], SKY, "#define CLOUDS\n#define CLOUDS_REFINED\n"],
  cloud_map: [[""], [...CLOUDY, "shaders/cloud_map.frag"]],
  cloud_behind: [[""], [...CLOUDY, "shaders/cloud_behind.frag"]],
  cloud_settle: [[""], [...CLOUDY, "shaders/cloud_level.frag"], "#define CLOUD_SETTLE\n"],
  cloud_level: [[""], [...CLOUDY, "shaders/cloud_level.frag"]],
  cloud_scatter: [["shaders/cloud_scatter.vert"], ["shaders/cloud_scatter.frag"]],
  stars: [[...LIBRARY.slice(0, 4), "shaders/stars.vert"],
          ["generated/constants.glsl", "shaders/camera.glsl", "shaders/stars.frag"]],
  cloudy_stars: [[...LIBRARY.slice(0, 4), "shaders/clouds.glsl", "shaders/stars.vert"],
                 ["generated/constants.glsl", "shaders/camera.glsl", "shaders/stars.frag"], "#define CLOUDS\n"],
  composite: [[""], ["generated/constants.glsl", "shaders/tonemap.glsl", "shaders/composite.frag"]],
  fast_transmittance: [[""], [...LIBRARY, "shaders/fast_model.glsl", "shaders/fast_transmittance.frag"]],
  fast_multiple: [[""], [...LIBRARY, "shaders/fast_model.glsl", "shaders/fast_multiple.frag"]],
  fast_irradiance: [[""], [...LIBRARY, "shaders/fast_model.glsl", "shaders/fast_irradiance.frag"]],
  fast_sky_view: [[""], [...LIBRARY, "shaders/fast_model.glsl", "shaders/fast_sky_view.frag"]],
  fast_sky: [[""], [...CLOUDY, "shaders/fast_model.glsl", "shaders/main.frag"], "#define FAST_MODEL\n"],
  fast_space: [[""], [...CLOUDY, "shaders/fast_model.glsl", "shaders/main.frag"],
               "#define FAST_MODEL\n#define FAST_SPACE\n"],
};
// What the page says is on screen (state.model)
const MODEL_LABELS = {fast: "fast model (Hillaire 2020)", tables: "precomputed tables"};
const PREFIX = "#version 300 es\nprecision highp float;\nprecision highp int;\nprecision highp sampler3D;\n";
const FULL_SCREEN = "in vec2 position;\nvoid main() { gl_Position = vec4(position, 0.0, 1.0); }\n";
const METER_SIZE = [64, 36];  // the auto-exposure meter renders the view this small
const DEG = Math.PI / 180;
const J2000_MS = Date.UTC(2000, 0, 1, 12);  // the clouds' epoch (api.J2000_UTC)
const CLOUD_UNITS = ["noise", "profiles", "phase", "optics"];  // texture units 4-7
const MAP_UNITS = ["low", "middle", "high"];  // the clouds' shadow map ...
const MAP_UNIT = 8;  // ... on texture units 8-10
const REFINE_UNIT = 11;  // texture units 11-13: the clouds' refinement (bindRefinement)
const MAP_GRID = 16;  // the shadow map is placed over the rays of (MAP_GRID + 1)^2 pixels

// Exposure change [EV] for a scene of log-average luminance L [cd m^-2] (twin of
// render.tonemap.night_compensation_ev, Krawczyk et al. 2005): 0 by day, down to a floor in
// twilight and at night
function nightCompensationEv(logAverage, exposure) {
  const key = (luminance) => 1.03 - 2.0 / (2.0 + Math.log10(luminance + 1.0));
  const shift = Math.log2(key(logAverage) / key(exposure.daylight_log_average_cd_m2));
  const meteredGrey = exposure.meter_calibration_k / (exposure.iso_speed * exposure.saturation_factor);
  return Math.max(shift, Math.log2(exposure.dark_scene_key / meteredGrey));
}

function compile(gl, type, source) {
  const shader = gl.createShader(type);
  gl.shaderSource(shader, source);
  gl.compileShader(shader);
  if (!gl.getShaderParameter(shader, gl.COMPILE_STATUS)) {
    throw new Error(`shader does not compile: ${gl.getShaderInfoLog(shader)}`);
  }
  return shader;
}

async function buildPrograms(gl) {
  const names = new Set(Object.values(PROGRAMS).flatMap(([vertex, fragment]) => [...vertex, ...fragment])
                                                 .filter((name) => name));
  const texts = {"": FULL_SCREEN};
  await Promise.all([...names].map(async (name) => { texts[name] = await (await fetch(`static/${name}`)).text(); }));
  const programs = {};
  for (const [key, [vertex, fragment, defines = ""]] of Object.entries(PROGRAMS)) {
    const program = gl.createProgram();
    gl.attachShader(program, compile(gl, gl.VERTEX_SHADER, PREFIX + defines + vertex.map((n) => texts[n]).join("\n")));
    gl.attachShader(program, compile(gl, gl.FRAGMENT_SHADER, PREFIX + defines + fragment.map((n) => texts[n]).join("\n")));
    const stars = key.endsWith("stars");
    gl.bindAttribLocation(program, 0, stars ? "a_direction" : "position");
    if (stars) gl.bindAttribLocation(program, 1, "a_irradiance");
    gl.linkProgram(program);
    if (!gl.getProgramParameter(program, gl.LINK_STATUS)) {
      throw new Error(`shader ${key} does not link: ${gl.getProgramInfoLog(program)}`);
    }
    programs[key] = program;
  }
  return programs;
}

class Viewer {
  constructor(canvas, layout, programs, state) {
    this.canvas = canvas;
    this.gl = canvas.getContext("webgl2");
    this.layout = layout;
    this.programs = programs;
    this.state = state;
    this.tables = null;
    this.tablesKey = null;  // the physical parameters of the tables (physicalKey)
    this.fast = null;  // the fast model of the current atmosphere (FastModel)
    this.fastDescriptions = new Map();  // atmosphere -> decoded description
    this.model = null;  // "fast" or "tables": what draws the sky
    this.stars = null;
    this.frameTimes = [];
    this.locations = new Map();
    const gl = this.gl;
    this.fullScreen = gl.createVertexArray();
    this.noAttributes = gl.createVertexArray();  // points placed by gl_VertexID
    this.targets = new Map();  // float render targets (textureTargets)
    this.spacings = new Map();  // its first lattice's spacing by projection and size
    gl.bindVertexArray(this.fullScreen);
    gl.bindBuffer(gl.ARRAY_BUFFER, gl.createBuffer());
    gl.bufferData(gl.ARRAY_BUFFER, new Float32Array([-1, -1, 3, -1, -1, 3]), gl.STATIC_DRAW);
    gl.enableVertexAttribArray(0);
    gl.vertexAttribPointer(0, 2, gl.FLOAT, false, 0, 0);
    gl.bindVertexArray(null);
    this.timer = gl.getExtension("EXT_disjoint_timer_query_webgl2");
    // Float render targets: the exposed frame (sky + stars) and the meter; without them the
    // sky is tone-mapped in one pass and the stars are left out
    this.floatTargets = gl.getExtension("EXT_color_buffer_float") !== null;
    this.query = null;
    this.gpuMs = null;
    this.clouds = uploadClouds(gl, null);
  }

  // Clouds from /api/clouds (decoded), or none (null)
  setClouds(decoded) {
    deleteClouds(this.gl, this.clouds);
    this.clouds = uploadClouds(this.gl, decoded);
    this.cloudsVersion = (this.cloudsVersion || 0) + 1;
    if (this.model === "fast" && !this.fastPossible() && this.tables) this.setModel("tables");
  }

  // The clouds' time [s] since their initial state: with a date, the seconds since J2000 (as
  // `render --time`), otherwise the page's cloud time (`render --cloud-time`)
  cloudTime() {
    const s = this.state;
    const date = s.time ? Date.parse(s.time) : NaN;
    return Number.isFinite(date) ? (date - J2000_MS) / 1000 : s.cloud_time;
  }

  // The clouds' uniforms for a camera at `position` (world [m]): each row's first columns of
  // the parameter table as the shader's u_cloud_params, with the wind's columns (OFFSET = wind
  // t, ALONG = its direction, in the site's east-north-up frame, as atmosphere.cloud_field with
  // to_world and time_s) and the coverage when the page sets it, and the noise coordinates of
  // the camera, three per layer (shape, weather, detail), reduced modulo the tile in double
  // precision (clouds.glsl)
  cloudUniforms(position) {
    const clouds = this.clouds;
    const header = clouds.header;
    const layers = header.n_layers;
    const max = this.layout.clouds.max_layers;
    const origins = new Float32Array(9 * max);
    const width = 4 * this.layout.clouds.param_vec4s;
    const packed = new Float32Array(width * max);
    if (!layers) {
      return {u_cloud_layers: 0, u_cloud_origin: origins, u_cloud_params: packed,
              u_cloud_texture_size: 1, u_cloud_ground_shade: [1, 1, 1]};
    }
    const s = this.state;
    const columns = this.layout.clouds.columns;
    const params = clouds.params;
    const stride = params.length / layers;
    const site = localFrame(s.site_lat * DEG, s.site_lon * DEG);
    const seconds = this.cloudTime();
    const n = header.texture_size;
    const wrap = (x) => ((x % n) + n) % n;
    for (let layer = 0; layer < layers; ++layer) {
      const row = layer * stride;
      const out = width * layer;
      packed.set(params.subarray(row, row + width), out);
      const [east, north] = header.wind_enu_m_s[layer];
      const wind = [0, 1, 2].map((i) => site[0][i] * east + site[1][i] * north);
      const speed = Math.hypot(...wind);
      const along = speed > 0 ? wind.map((v) => v / speed) : site[0];
      const offset = wind.map((v) => v * s.wind * seconds);
      ["OFFSET_X", "OFFSET_Y", "OFFSET_Z"].forEach((key, i) => { packed[out + columns[key]] = offset[i]; });
      ["ALONG_X", "ALONG_Y", "ALONG_Z"].forEach((key, i) => { packed[out + columns[key]] = along[i]; });
      if (s.cloud_coverage >= 0) packed[out + columns.COVERAGE] = s.cloud_coverage;
      const stretch = params[row + columns.STRETCH_MINUS_ONE];
      const c = position.map((v, i) => v - offset[i]);
      const shift = dot(c, along) * stretch / (1 + stretch);
      const m = c.map((v, i) => v - shift * along[i]);
      const tile = params[row + columns.INV_SCALE] * n;
      const large = tile / this.layout.clouds.coverage_tile_ratio;
      const fine = params[row + columns.INV_DETAIL_SCALE] * n;
      origins.set(m.map((v) => wrap(v * tile)), 9 * layer);
      origins.set([m[2], m[0], m[1]].map((v) => wrap(v * large)), 9 * layer + 3);
      origins.set(m.map((v) => wrap(v * fine)), 9 * layer + 6);
    }
    return {u_cloud_layers: layers, u_cloud_origin: origins, u_cloud_params: packed,
            u_cloud_texture_size: n, u_cloud_ground_shade: header.ground_shade_xyz};
  }

  // The cloud textures on units 4-7 (always bound: stand-ins without clouds) and their
  // `uniforms` (cloudUniforms)
  bindClouds(program, uniforms) {
    const gl = this.gl;
    CLOUD_UNITS.forEach((key, i) => {
      gl.activeTexture(gl.TEXTURE4 + i);
      gl.bindTexture(key === "noise" ? gl.TEXTURE_3D : gl.TEXTURE_2D, this.clouds.textures[key]);
      gl.uniform1i(this.uniform(program, `u_cloud_${key}`), 4 + i);
    });
    this.setUniforms(program, uniforms);
  }

  // Where the clouds' shadow map lies for the view at w x h (geometry.js mapFrame over the
  // rays of a grid of its pixels and, for a fisheye, of its rim), or null
  cloudMapFrame(view, width, height) {
    const s = this.state;
    const {columns, shadow_map: map} = this.layout.clouds;
    const params = this.clouds.params;
    const stride = params.length / this.clouds.header.n_layers;
    const radii = (column) => Array.from({length: this.clouds.header.n_layers},
                                         (_, layer) => params[layer * stride + column]);
    const [lowR, highR] = [Math.min(...radii(columns.BASE_R)), Math.max(...radii(columns.TOP_R))];
    const frame = localFrame(s.lat * DEG, s.lon * DEG);
    const size = {clientWidth: width, clientHeight: height};
    const rays = [];
    for (let i = 0; i <= MAP_GRID; ++i) {
      for (let j = 0; j <= MAP_GRID; ++j) {
        rays.push(toWorld(frame, pixelDirection(s, size, i * width / MAP_GRID, j * height / MAP_GRID)));
      }
    }
    if (s.projection === "fisheye") {  // its rim, where the rays reach farthest
      const radius = Math.min(width, height) / 2;
      for (let k = 0; k < 4 * MAP_GRID; ++k) {
        const angle = 2 * Math.PI * k / (4 * MAP_GRID);
        rays.push(toWorld(frame, pixelDirection(s, size, width / 2 + radius * Math.cos(angle),
                                                height / 2 + radius * Math.sin(angle))));
      }
    }
    const stretches = rays.map((ray) => shadedStretch(view.u_camera_position, ray, this.tables.header.bottom_radius_m,
                                                      highR, map.shadow_max_m));
    return mapFrame(rays, stretches, view.u_sun_direction, lowR, highR, map);
  }

  // The clouds' shadow map for the view (cloud_map.frag, one pass a layer into its rows of the
  // three textures), drawn again only when where it lies, the sun or the clouds changed; its
  // uniforms for the sky ({u_map_on: 0}: no map without float render targets or where its
  // texels would be too coarse, views from space; then no shadows in the air)
  drawCloudMap(view, clouds) {
    const place = this.floatTargets ? this.cloudMapFrame(view, ...view.u_resolution) : null;
    if (!place) return {u_map_on: 0};
    const gl = this.gl;
    const layers = this.clouds.header.n_layers;
    const [nU, nW] = place.shape;
    const uniforms = {u_map_on: 1, u_map_e1: place.e1, u_map_e2: place.e2, u_map_corner: place.corner,
                      u_map_texel: place.texel, u_map_size: place.shape, u_map_levels: place.levels};
    const key = JSON.stringify([uniforms, view.u_camera_position, view.u_sun_direction, this.cloudsVersion,
                                Array.from(clouds.u_cloud_params)]);
    if (key === this.mapKey) return uniforms;
    const previous = gl.getParameter(gl.FRAMEBUFFER_BINDING);
    MAP_UNITS.forEach((_, i) => {  // not read while drawn into
      gl.activeTexture(gl.TEXTURE0 + MAP_UNIT + i);
      gl.bindTexture(gl.TEXTURE_2D, null);
    });
    const targets = this.textureTargets("map", nU, nW * layers, MAP_UNITS.length,
                                        {format: gl.RGBA16F, filter: gl.LINEAR});
    gl.bindFramebuffer(gl.FRAMEBUFFER, targets.framebuffer);
    gl.useProgram(this.programs.cloud_map);
    this.bindClouds("cloud_map", clouds);
    this.setUniforms("cloud_map", {...uniforms, u_camera_position: view.u_camera_position,
                                   u_sun_direction: view.u_sun_direction});
    gl.bindVertexArray(this.fullScreen);
    for (let layer = 0; layer < layers; ++layer) {
      gl.viewport(0, layer * nW, nU, nW);
      this.setUniforms("cloud_map", {u_map_layer: layer});
      gl.drawArrays(gl.TRIANGLES, 0, 3);
    }
    gl.bindFramebuffer(gl.FRAMEBUFFER, previous);
    this.mapKey = key;
    return uniforms;
  }

  // Float render targets: textures of w x h, `count` of them (`format`, RGBA32F unless given;
  // `filter`, NEAREST unless given; edges clamped), attached to one framebuffer (its draw
  // buffers) with a depth buffer if `depth`, kept as this.targets[name]
  textureTargets(name, width, height, count, {format = this.gl.RGBA32F, filter = this.gl.NEAREST,
                                              depth = false} = {}) {
    const gl = this.gl;
    const old = this.targets.get(name);
    if (old && old.width === width && old.height === height) return old;
    if (old) {
      old.textures.forEach((t) => gl.deleteTexture(t));
      if (old.depth) gl.deleteRenderbuffer(old.depth);
      gl.deleteFramebuffer(old.framebuffer);
    }
    const framebuffer = gl.createFramebuffer();
    gl.bindFramebuffer(gl.FRAMEBUFFER, framebuffer);
    const textures = Array.from({length: count}, (_, i) => {
      const texture = gl.createTexture();
      gl.bindTexture(gl.TEXTURE_2D, texture);
      gl.texImage2D(gl.TEXTURE_2D, 0, format, width, height, 0, gl.RGBA, gl.FLOAT, null);
      for (const [key, value] of [[gl.TEXTURE_MIN_FILTER, filter], [gl.TEXTURE_MAG_FILTER, filter],
                                  [gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE], [gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE]]) {
        gl.texParameteri(gl.TEXTURE_2D, key, value);
      }
      gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0 + i, gl.TEXTURE_2D, texture, 0);
      return texture;
    });
    gl.drawBuffers(textures.map((_, i) => gl.COLOR_ATTACHMENT0 + i));
    const buffer = depth ? gl.createRenderbuffer() : null;
    if (buffer) {
      gl.bindRenderbuffer(gl.RENDERBUFFER, buffer);
      gl.renderbufferStorage(gl.RENDERBUFFER, gl.DEPTH_COMPONENT24, width, height);
      gl.framebufferRenderbuffer(gl.FRAMEBUFFER, gl.DEPTH_ATTACHMENT, gl.RENDERBUFFER, buffer);
    }
    this.targets.set(name, {textures, framebuffer, depth: buffer, width, height});
    return this.targets.get(name);
  }

  // `program`'s samplers of the refinement: [name, targets, which texture (0)] on units 11-13;
  // no other texture stays bound there (a pass may draw into it)
  bindRefinement(program, samplers) {
    const gl = this.gl;
    for (let i = 0; i < 3; ++i) {
      gl.activeTexture(gl.TEXTURE0 + REFINE_UNIT + i);
      gl.bindTexture(gl.TEXTURE_2D, null);
    }
    samplers.forEach(([name, targets, which = 0], i) => {
      gl.activeTexture(gl.TEXTURE0 + REFINE_UNIT + i);
      gl.bindTexture(gl.TEXTURE_2D, targets.textures[which]);
      gl.uniform1i(this.uniform(program, name), REFINE_UNIT + i);
    });
  }

  // The clouds of the view by adaptive refinement over the pixels (twin of
  // transport.adaptive_pixels.refine, as transport.clouds.clouds_in_front uses it): the
  // radiance behind them (cloud_behind.frag), then a lattice of every s-th pixel marched and,
  // level by level, the pixels between (cloud_level.frag on a compact grid, put in place by
  // cloud_scatter); main.frag with CLOUDS_REFINED composes the frame from what this returns,
  // the targets {behind, known} (`uniforms`: the view's and the shadow map's; `clouds`:
  // cloudUniforms; `slot`: "frame" or "meter", each its own)
  drawRefinedClouds(uniforms, clouds, slot) {
    const gl = this.gl;
    const [width, height] = uniforms.u_resolution;
    const previous = gl.getParameter(gl.FRAMEBUFFER_BINDING);
    const s = this.state;
    const refinement = this.layout.clouds.refinement;
    const key = JSON.stringify([s.projection, s.fov, s.fisheye_fov, width, height]);
    if (!this.spacings.has(key)) {  // the rays' angles do not turn with the camera
      this.spacings.set(key, coarseSpacing(s, width, height, refinement.max_spacing,
                                           refinement.spacing_angle_rad));
    }
    let spacing = this.spacings.get(key);
    const behind = this.textureTargets(`${slot} behind`, width, height, 1);
    const known = this.textureTargets(`${slot} known`, width, height, 2);
    const grid = spacing > 1 ? [Math.ceil(width / 2), Math.ceil(height / 2)] : [width, height];
    const level = this.textureTargets(`${slot} level`, ...grid, 2, {depth: true});
    const setUp = (program) => {
      gl.useProgram(this.programs[program]);
      this.bindTables(program);
      this.bindClouds(program, clouds);
      this.bindCloudMap(program);
      this.setUniforms(program, uniforms);
    };
    gl.bindFramebuffer(gl.FRAMEBUFFER, behind.framebuffer);
    gl.viewport(0, 0, width, height);
    setUp("cloud_behind");
    this.bindRefinement("cloud_behind", []);
    gl.bindVertexArray(this.fullScreen);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
    const passes = [[spacing, 0, 0]];  // the lattice, then three offsets a level
    for (let half = spacing >> 1; half >= 1; spacing = half, half >>= 1) {
      passes.push([spacing, 0, half], [spacing, half, 0], [spacing, half, half]);
    }
    const inputs = [["u_behind", behind], ["u_known_t", known], ["u_known_a", known, 1]];
    passes.forEach((pass, index) => {
      const [step, dy, dx] = pass;
      const columns = Math.ceil((width - dx) / step);
      const rows = Math.ceil((height - dy) / step);
      gl.bindFramebuffer(gl.FRAMEBUFFER, level.framebuffer);
      gl.viewport(0, 0, columns, rows);
      gl.bindVertexArray(this.fullScreen);
      gl.depthMask(true);
      gl.clear(gl.DEPTH_BUFFER_BIT);  // 1: every pixel left to march
      gl.enable(gl.DEPTH_TEST);
      if (index > 0) {  // the settled pixels: depth 0
        setUp("cloud_settle");
        this.bindRefinement("cloud_settle", inputs);
        this.setUniforms("cloud_settle", {u_level: pass});
        gl.depthFunc(gl.ALWAYS);
        gl.drawArrays(gl.TRIANGLES, 0, 3);
      }
      setUp("cloud_level");  // the rest, at depth 0.5
      this.bindRefinement("cloud_level", inputs);
      this.setUniforms("cloud_level", {u_level: pass});
      gl.depthFunc(gl.LESS);
      gl.depthMask(false);
      gl.drawArrays(gl.TRIANGLES, 0, 3);
      gl.depthMask(true);
      gl.disable(gl.DEPTH_TEST);
      gl.bindFramebuffer(gl.FRAMEBUFFER, known.framebuffer);
      gl.viewport(0, 0, width, height);
      gl.useProgram(this.programs.cloud_scatter);
      this.bindRefinement("cloud_scatter", [["u_level_t", level], ["u_level_a", level, 1]]);
      this.setUniforms("cloud_scatter", {u_level: pass, u_level_columns: columns, u_resolution: [width, height]});
      gl.bindVertexArray(this.noAttributes);
      gl.drawArrays(gl.POINTS, 0, columns * rows);
    });
    gl.bindFramebuffer(gl.FRAMEBUFFER, previous);
    return {behind, known};
  }

  // The shadow map's textures on units 8-10
  bindCloudMap(program) {
    const gl = this.gl;
    MAP_UNITS.forEach((key, i) => {
      gl.activeTexture(gl.TEXTURE0 + MAP_UNIT + i);
      const map = this.targets.get("map");
      gl.bindTexture(gl.TEXTURE_2D, map ? map.textures[i] : null);
      gl.uniform1i(this.uniform(program, `u_cloud_map_${key}`), MAP_UNIT + i);
    });
  }

  uniform(program, name) {
    const key = `${program}:${name}`;
    if (!this.locations.has(key)) this.locations.set(key, this.gl.getUniformLocation(this.programs[program], name));
    return this.locations.get(key);
  }

  // Stars from /api/sky: {count, directions_enu, irradiance_xyz} in the site's frame
  setStars(stars) {
    const gl = this.gl;
    if (this.stars) gl.deleteVertexArray(this.stars.vao);
    const vao = gl.createVertexArray();
    gl.bindVertexArray(vao);
    [[0, stars.directions_enu], [1, stars.irradiance_xyz]].forEach(([index, values]) => {
      gl.bindBuffer(gl.ARRAY_BUFFER, gl.createBuffer());
      gl.bufferData(gl.ARRAY_BUFFER, new Float32Array(values), gl.STATIC_DRAW);
      gl.enableVertexAttribArray(index);
      gl.vertexAttribPointer(index, 3, gl.FLOAT, false, 0, 0);
    });
    gl.bindVertexArray(null);
    this.stars = {vao, count: stars.count};
    this.starsVersion = (this.starsVersion || 0) + 1;
  }

  setTables(decoded) {
    deleteTables(this.gl, this.tables);
    this.tables = uploadTables(this.gl, decoded);
    this.tablesVersion = (this.tablesVersion || 0) + 1;
  }

  // The header of what draws the sky (radii, the star)
  header() {
    return this.model === "fast" ? this.fast.header : this.tables.header;
  }

  // The physical parameters the picture depends on
  physicalKey() {
    const s = this.state;
    return JSON.stringify([s.atmosphere, s.amounts, s.albedo]);
  }

  // Whether the fast model can draw this view: float render targets, and no clouds (their
  // march needs the tables)
  fastPossible() {
    return this.floatTargets && this.clouds.header.n_layers === 0;
  }

  // Shows the state's physical parameters with the fast model at once, unless the tables
  // already hold them: loads the atmosphere's description (once), makes the LUTs again and
  // draws; records the change-to-image time (this.lastFastChange). Returns whether it drew.
  async showFast() {
    const s = this.state;
    const key = this.physicalKey();
    if (!this.fastPossible() || key === this.tablesKey) return false;
    const started = performance.now();
    if (!this.fastDescriptions.has(s.atmosphere)) {
      const response = await apiFetch(`fast?atmosphere=${encodeURIComponent(s.atmosphere)}`);
      if (!response.ok) throw new Error((await response.json().catch(() => ({error: response.statusText}))).error);
      this.fastDescriptions.set(s.atmosphere, decodeFast(await response.arrayBuffer(), this.layout));
    }
    return this.applyFast(started);
  }

  // The fast model of the state's parameters on screen now (its description loaded)
  applyFast(started = performance.now()) {
    const s = this.state;
    const key = this.physicalKey();
    const decoded = this.fastDescriptions.get(s.atmosphere);
    if (!decoded || !this.fastPossible() || key === this.tablesKey) return false;
    if (key === this.fastKey && this.model === "fast") return false;  // on screen already
    if (!this.fast || this.fast.header !== decoded.header) {
      if (this.fast) this.fast.delete();
      this.fast = new FastModel(this, decoded);
    }
    const gl = this.gl;
    const pixel = new Uint8Array(4);
    this.fast.compute(s.amounts, s.albedo);
    this.fastKey = key;
    this.setModel("fast");
    const view = this.viewUniforms(this.canvas.width || 1, this.canvas.height || 1);
    this.fast.skyView(view.u_camera_position, view.u_sun_direction);
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);  // waits for the LUTs
    const luts = performance.now();
    this.frame();
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);  // waits for the frame
    const shown = performance.now();
    this.lastFastChange = {total_ms: shown - started, luts_ms: luts - started, draw_ms: shown - luts};
    return true;
  }

  setModel(model) {
    this.model = model;
    this.modelVersion = (this.modelVersion || 0) + 1;
    document.body.dataset.model = model;
    const label = document.getElementById("model");
    if (label) label.textContent = MODEL_LABELS[model];
  }

  // The camera and sun uniforms of the current state for a w x h image
  viewUniforms(width, height) {
    const s = this.state;
    const radius = this.header().bottom_radius_m;
    const frame = localFrame(s.lat * DEG, s.lon * DEG);
    const position = frame[2].map((v) => v * (radius + s.altitude_m));
    const siteFrame = localFrame(s.site_lat * DEG, s.site_lon * DEG);
    const sun = toWorld(siteFrame, sunDirection(s.sun_zenith, s.sun_azimuth));
    const [right, up, forward] = cameraBasis(s.heading * DEG, s.pitch * DEG, s.roll * DEG);
    const tanV = Math.tan(s.fov * DEG / 2);
    const projection = this.layout.projections.indexOf(s.projection);
    return {
      u_resolution: [width, height],
      u_projection: projection,
      u_half_extent: [tanV * width / height, tanV],
      u_camera_basis: [...right, ...up, ...forward],
      u_fisheye_theta_max: s.fisheye_fov * DEG / 2,
      u_local_to_world: [...frame[0], ...frame[1], ...frame[2]],
      u_site_to_world: [...siteFrame[0], ...siteFrame[1], ...siteFrame[2]],
      u_camera_position: position,
      u_sun_direction: sun,
      u_exposure: Math.pow(2, s.compensation) / (this.layout.exposure.saturation_factor * Math.pow(2, s.ev100)),
      u_sun_light_stops: s.time ? Math.log2(s.sun_light_scale ?? 1) : 0,
      u_operator: this.layout.operators.indexOf(s.operator),
    };
  }

  setUniforms(program, values) {
    const gl = this.gl;
    const ints = new Set(["u_projection", "u_operator", "u_n_tables", "u_n_single", "u_phase_rows",
                          "u_output", "u_radius_warp_identity", "u_cloud_layers", "u_map_on",
                          "u_map_layer", "u_level_columns"]);
    const matrices = new Set(["u_camera_basis", "u_local_to_world", "u_site_to_world"]);
    for (const [name, value] of Object.entries(values)) {
      const location = this.uniform(program, name);
      if (location === null) continue;
      if (ints.has(name)) gl.uniform1i(location, value);
      else if (matrices.has(name)) gl.uniformMatrix3fv(location, false, value);
      else if (name === "u_scattering_scales") gl.uniform1fv(location, value);
      else if (name === "u_sun_disk") gl.uniform3fv(location, value);
      else if (name === "u_radius_warp") gl.uniform4fv(location, value);
      else if (name === "u_cloud_origin") gl.uniform3fv(location, value);
      else if (name === "u_cloud_params") gl.uniform4fv(location, value);
      else if (name === "u_level") gl.uniform3iv(location, value);
      else if (!Array.isArray(value)) gl.uniform1f(location, value);
      else if (value.length === 2) gl.uniform2fv(location, value);
      else if (value.length === 3) gl.uniform3fv(location, value);
      else if (value.length === 4) gl.uniform4fv(location, value);
    }
  }

  bindTables(program) {
    const gl = this.gl;
    const units = [["u_transmittance", gl.TEXTURE_2D, "transmittance"], ["u_irradiance", gl.TEXTURE_2D, "irradiance"],
                   ["u_scattering", gl.TEXTURE_3D, "scattering"], ["u_phase", gl.TEXTURE_2D, "phase"]];
    units.forEach(([name, target, key], unit) => {
      gl.activeTexture(gl.TEXTURE0 + unit);
      gl.bindTexture(target, this.tables.textures[key]);
      gl.uniform1i(this.uniform(program, name), unit);
    });
    this.setUniforms(program, this.tables.uniforms);
  }

  // The sky pass into the bound framebuffer (w x h): output "display", "meter" or "exposed"
  drawSky(width, height, output) {
    const gl = this.gl;
    if (this.model === "fast") {
      const view = this.viewUniforms(width, height);
      this.fast.skyView(view.u_camera_position, view.u_sun_direction);
      const space = Math.hypot(...view.u_camera_position) > this.fast.header.top_radius_m;
      const program = space ? "fast_space" : "fast_sky";
      gl.useProgram(this.programs[program]);
      gl.viewport(0, 0, width, height);
      this.fast.bind(program, 0);
      this.setUniforms(program, {...view, u_output: this.layout.outputs.indexOf(output)});
      gl.bindVertexArray(this.fullScreen);
      gl.drawArrays(gl.TRIANGLES, 0, 3);
      return;
    }
    const cloudy = this.clouds.header.n_layers > 0;
    const refined = cloudy && this.floatTargets;
    const program = refined ? "cloud_final" : cloudy ? "cloudy_sky" : "sky";
    const view = this.viewUniforms(width, height);
    const clouds = this.cloudUniforms(view.u_camera_position);
    const map = cloudy ? this.drawCloudMap(view, clouds) : {};
    const targets = refined ? this.drawRefinedClouds({...view, ...map}, clouds,
                                                     output === "meter" ? "meter" : "frame") : null;
    gl.useProgram(this.programs[program]);
    gl.viewport(0, 0, width, height);
    this.bindTables(program);
    this.bindClouds(program, clouds);
    if (cloudy) this.bindCloudMap(program);
    if (refined) this.bindRefinement(program, [["u_behind", targets.behind], ["u_known_t", targets.known],
                                               ["u_known_a", targets.known, 1]]);
    this.setUniforms(program, {...view, ...map, u_output: this.layout.outputs.indexOf(output)});
    gl.bindVertexArray(this.fullScreen);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
  }

  // The whole frame into the canvas: sky and sun (exposed, float), stars added, tone-mapped
  draw(width, height) {
    const gl = this.gl;
    if (!this.floatTargets) {
      this.drawSky(width, height, "display");
      return;
    }
    const frame = this.textureTargets("frame", width, height, 1, {format: gl.RGBA16F});  // blendable
    gl.bindFramebuffer(gl.FRAMEBUFFER, frame.framebuffer);
    this.drawSky(width, height, "exposed");
    if (this.stars && this.stars.count && this.model === "tables") {  // their light's path: the tables
      const stars = this.clouds.header.n_layers > 0 ? "cloudy_stars" : "stars";
      const view = this.viewUniforms(width, height);
      gl.useProgram(this.programs[stars]);
      this.bindTables(stars);
      this.bindClouds(stars, this.cloudUniforms(view.u_camera_position));
      this.setUniforms(stars, view);
      gl.enable(gl.BLEND);
      gl.blendFunc(gl.ONE, gl.ONE);
      gl.bindVertexArray(this.stars.vao);
      gl.drawArrays(gl.POINTS, 0, this.stars.count);
      gl.disable(gl.BLEND);
    }
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    gl.useProgram(this.programs.composite);
    gl.viewport(0, 0, width, height);
    gl.activeTexture(gl.TEXTURE0);
    gl.bindTexture(gl.TEXTURE_2D, frame.textures[0]);
    gl.uniform1i(this.uniform("composite", "u_frame"), 0);
    gl.uniform1i(this.uniform("composite", "u_operator"), this.layout.operators.indexOf(this.state.operator));
    gl.bindVertexArray(this.fullScreen);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
  }

  // The canvas fills the window (in device pixels) unless the address fixed its width or height
  resize() {
    const s = this.state;
    const width = s.width || Math.round(window.innerWidth * (window.devicePixelRatio || 1));
    const height = s.height || Math.round(window.innerHeight * (window.devicePixelRatio || 1));
    if (this.canvas.width !== width || this.canvas.height !== height) {
      this.canvas.width = width;
      this.canvas.height = height;
    }
  }

  // Draws a frame when the view changed since the last one (an idle page costs nothing)
  frame() {
    if (!this.model) return false;
    this.resize();
    // what the picture depends on: the view, not the physical parameters (those act through
    // new tables, so a slider does not redraw the old ones while the server computes)
    const {amounts, albedo, atmosphere, quality, ...view} = this.state;
    const signature = JSON.stringify([view, this.tablesVersion, this.starsVersion, this.cloudsVersion,
                                      this.modelVersion, this.canvas.width, this.canvas.height]);
    if (signature === this.drawn) return false;
    this.drawn = signature;
    const gl = this.gl;
    const measuring = this.timer && !this.query;
    if (measuring) {
      this.query = gl.createQuery();
      gl.beginQuery(this.timer.TIME_ELAPSED_EXT, this.query);
    }
    this.draw(this.canvas.width, this.canvas.height);
    if (measuring) gl.endQuery(this.timer.TIME_ELAPSED_EXT);
    return true;
  }

  // GPU time of the last measured frame [ms] (EXT_disjoint_timer_query_webgl2), or null
  pollTimer() {
    const gl = this.gl;
    if (this.query && gl.getQueryParameter(this.query, gl.QUERY_RESULT_AVAILABLE)) {
      if (!gl.getParameter(this.timer.GPU_DISJOINT_EXT)) {
        this.gpuMs = gl.getQueryParameter(this.query, gl.QUERY_RESULT) / 1e6;
      }
      gl.deleteQuery(this.query);
      this.query = null;
    }
    return this.gpuMs;
  }

  // EV100 a meter would choose for the current view, as `render --time` meters
  // (api.save_image with adapt_to_night): from space the incident-light meter on the sunlight
  // (tonemap.incident_ev100), else the reflected-light meter on the sky pixels, each luminance
  // held at least at the natural night sky's, less the night compensation of their log-average
  // (twin of render.tonemap.night_adapted_exposure)
  meter() {
    const header = this.header();
    const exposure = this.layout.exposure;
    if (this.state.altitude_m > header.top_radius_m - header.bottom_radius_m) {
      const lux = header.sun_irradiance_xyz[1];
      return Math.log2(lux * exposure.iso_speed / exposure.incident_calibration_c);
    }
    const [w, h] = METER_SIZE;
    if (!this.floatTargets) return null;  // no float render targets: exposure by hand
    const p = this.meterPixels("meter", w, h);
    // log-luminance sums of the pixels to meter, as render.scene.sky_image picks them: those
    // looking above the horizontal, else the lit ones, else all inside the image (alpha 1)
    const sums = {sky: [0, 0], lit: [0, 0], valid: [0, 0]};
    const add = (key, value) => { sums[key][0] += value; sums[key][1] += 1; };
    for (let i = 0; i < w * h; ++i) {
      const luminance = p[4 * i];
      if (!(p[4 * i + 3] > 0.5) || !Number.isFinite(luminance)) continue;
      const logLuminance = Math.log(Math.max(luminance, exposure.natural_night_sky_cd_m2));
      add("valid", logLuminance);
      if (luminance > 0) add("lit", logLuminance);
      if (p[4 * i + 1] > 0.5) add("sky", logLuminance);
    }
    const [sum, count] = [sums.sky, sums.lit, sums.valid].find(([, n]) => n > 0) || [0, 0];
    if (!count) return null;
    const logAverage = Math.exp(sum / count);
    const metered = Math.log2(logAverage * exposure.iso_speed / exposure.meter_calibration_k);
    return metered - nightCompensationEv(logAverage, exposure);
  }

  // The sky pass's "meter" output at width x height into the float target `name`, read back:
  // RGBA floats [Y, up, -, alpha] row-major from the bottom row
  meterPixels(name, width, height) {
    const gl = this.gl;
    const target = this.textureTargets(name, width, height, 1);
    gl.bindFramebuffer(gl.FRAMEBUFFER, target.framebuffer);
    this.drawSky(width, height, "meter");
    const p = new Float32Array(width * height * 4);
    gl.readPixels(0, 0, width, height, gl.RGBA, gl.FLOAT, p);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    return p;
  }

  // The luminance Y [cd m^-2] of the view at w x h as the sky pass computes it and whether
  // each pixel looks up (output "meter": [Y, up] row-major from the bottom row), for tests
  luminance(width, height) {
    const p = this.meterPixels("luminance", width, height);
    return Array.from({length: width * height}, (_, i) => [p[4 * i], p[4 * i + 1]]);
  }

  // Milliseconds per frame over n frames drawn back to back, each waited for (readPixels)
  benchmark(n) {
    const gl = this.gl;
    const pixel = new Uint8Array(4);
    this.draw(this.canvas.width, this.canvas.height);
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
    const start = performance.now();
    for (let i = 0; i < n; ++i) {
      this.draw(this.canvas.width, this.canvas.height);
      gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
    }
    return (performance.now() - start) / n;
  }
}

async function loadTables(viewer, query, onProgress) {
  const done = {value: false};
  const poll = async () => {
    while (!done.value) {
      try {
        const progress = await apiJson("progress");
        if (!done.value) onProgress(progress);
      } catch (error) { /* the server is busy answering; try again */ }
      await new Promise((resolve) => setTimeout(resolve, 200));
    }
  };
  poll();
  try {
    const response = await apiFetch(`tables?${query}`);
    if (!response.ok) {
      const message = (await response.json().catch(() => ({error: response.statusText}))).error;
      const error = new Error(message);
      error.status = response.status;
      throw error;
    }
    return decodeTables(await response.arrayBuffer(), viewer.layout);
  } finally {
    done.value = true;
  }
}

// The clouds the state names (state.clouds; "none": a clear sky) over the state's planet
async function loadClouds(viewer) {
  const state = viewer.state;
  if (state.clouds === "none") {
    viewer.setClouds(null);
    return;
  }
  const params = new URLSearchParams({clouds: state.clouds, atmosphere: state.atmosphere});
  const response = await apiFetch(`clouds?${params}`);
  if (!response.ok) {
    const message = (await response.json().catch(() => ({error: response.statusText}))).error;
    throw new Error(message);
  }
  viewer.setClouds(decodeClouds(await response.arrayBuffer(), viewer.layout));
}

// The sun and the stars for a time and place from the server's ephemeris; the site moves
// there (and a ground camera with it). Throws with the server's message for a bad input.
async function applySky(viewer, time, lat, lon) {
  const state = viewer.state;
  const params = new URLSearchParams({atmosphere: state.atmosphere, time, lat, lon});
  const answer = await apiJson(`sky?${params}`);
  state.site_lat = Number(lat);
  state.site_lon = Number(lon);
  if (state.mode === "ground") { state.lat = state.site_lat; state.lon = state.site_lon; }
  state.sun_zenith = answer.sun_zenith_deg;
  state.sun_azimuth = answer.sun_azimuth_deg;
  state.sun_light_scale = answer.sun_light_scale;  // the sun's distance that day
  state.time = time;
  viewer.setStars(answer.stars);
  return answer;
}

async function main() {
  const canvas = document.getElementById("sky");
  const gl = canvas.getContext("webgl2", {antialias: false, alpha: false, preserveDrawingBuffer: true});
  if (!gl) {
    showError("This browser has no WebGL2; the viewer needs it (any current Chrome, Firefox, Safari or Edge).");
    return;
  }
  const [layout, programs, description] = await Promise.all([
    fetchLayout(), buildPrograms(gl), apiJson("atmospheres")]);
  const state = readUrlState(description, layout);
  const viewer = new Viewer(canvas, layout, programs, state);
  canvas.classList.toggle("fixed-size", Boolean(state.width || state.height));
  let request = 0;
  const showFastStatus = () => {
    const fast = viewer.lastFastChange;
    showStatus(`fast model: image ${fast.total_ms.toFixed(0)} ms after the change (LUTs ${fast.luts_ms.toFixed(0)} ms, ` +
               `draw ${fast.draw_ms.toFixed(0)} ms); computing the tables`);
  };
  // A physical parameter changed (or the page starts): the fast model shows it at once, the
  // tables of the server follow and take over
  const reload = async () => {
    const mine = ++request;
    const key = viewer.physicalKey();
    const params = new URLSearchParams({atmosphere: state.atmosphere});
    if (state.albedo !== null) params.set("albedo", state.albedo);
    for (const [name, value] of Object.entries(state.amounts)) params.set(`amount_${name}`, value);
    const started = performance.now();
    const qualities = state.quality === "full" ? ["preview", "full"] : [state.quality];
    const fetchQuality = (quality) => {
      params.set("quality", quality);
      return loadTables(viewer, params.toString(), showProgress);
    };
    const first = fetchQuality(qualities[0]);  // the server starts while the page draws the fast model
    first.catch(() => {});  // handled below
    try {
      if (await viewer.showFast() && mine === request) showFastStatus();
    } catch (error) {
      showError(error.message);
    }
    for (const [index, quality] of qualities.entries()) {
      try {
        const decoded = await (index === 0 ? first : fetchQuality(quality));
        if (mine !== request) return;
        const received = performance.now();
        viewer.setTables(decoded);
        viewer.tablesKey = key;
        viewer.setModel("tables");
        viewer.frame();
        viewer.gl.readPixels(0, 0, 1, 1, viewer.gl.RGBA, viewer.gl.UNSIGNED_BYTE, new Uint8Array(4));  // waits for the frame
        const shown = performance.now();
        viewer.lastChange = {total_ms: shown - started, tables_ms: received - started, draw_ms: shown - received};
        showStatus(`${decoded.header.label}: ${decoded.header.n_wavelengths} wavelengths, ` +
                   `${decoded.header.orders} orders; image ${(shown - started).toFixed(0)} ms after the change ` +
                   `(tables ${(received - started).toFixed(0)} ms, upload and draw ${(shown - received).toFixed(0)} ms)`);
        document.body.dataset.tables = quality;
      } catch (error) {
        if (mine !== request) return;
        if (error.status === 409) return;  // superseded by a newer request
        showError(error.message);
        return;
      } finally {
        showProgress({busy: false});
      }
    }
  };
  const sky = (time, lat, lon) => applySky(viewer, time, lat, lon);
  const reloadClouds = async () => {
    try {
      await loadClouds(viewer);
      document.body.dataset.clouds = state.clouds;
    } catch (error) {
      showError(error.message);
    }
  };
  // a slider moved: the fast model at once, the tables after a pause (a dragged slider asks
  // the server for its last value only)
  let pause = null;
  const physicalChanged = () => {
    if (viewer.applyFast()) showFastStatus();
    clearTimeout(pause);
    pause = setTimeout(reload, 150);
  };
  window.skyscatter = {viewer, state, reload, sky, reloadClouds, physicalChanged,
                       benchmark: (n) => viewer.benchmark(n)};
  const refreshControls = bindControls(viewer, description, reload, sky, reloadClouds, physicalChanged);
  // Frame times: the intervals between animation frames that drew (while the view moves)
  let previous = null;
  const loop = (time) => {
    if (viewer.frame()) {
      if (previous !== null && time - previous < 2000) {
        viewer.frameTimes.push(time - previous);
        if (viewer.frameTimes.length > 30) viewer.frameTimes.shift();
      }
      previous = time;
    } else {
      previous = null;
    }
    viewer.pollTimer();
    requestAnimationFrame(loop);
  };
  await Promise.all([reload(), reloadClouds()]);
  viewer.frame();
  if (state.time) {
    try { await sky(state.time, state.site_lat, state.site_lon); } catch (error) { showError(error.message); }
    refreshControls();
    viewer.frame();
  }
  document.body.dataset.ready = "1";
  requestAnimationFrame(loop);
}

main().catch((error) => showError(error.message));
