// A cube map from skyscatter lighting a diffuse sphere, in plain WebGL2 (no library, no
// network): what an engine does with `skyscatter render --camera cubemap --exr sky.hdr
// --light light.json` (docs/engines.md). The page
//   1. reads the Radiance .hdr (RGBE, Ward 1991; skyscatter writes flat scanlines) into
//      linear RGB floats, 1.0 = 1 cd m^-2 of luminance;
//   2. cuts the cross (4 x 3 faces) or strip (6 x 1) into the six faces of a cube map texture
//      (OpenGL 4.6 section 8.13: each face's top row is its first row, t = 0);
//   3. draws the map as the background and a sphere of albedo a lit by the light file:
//      L = a / pi (E_sh(n) + E_sun max(n . s, 0)), E_sh(n) = sum E_lm Y_lm(n) (Ramamoorthi &
//      Hanrahan 2001, doi:10.1145/383259.383317), in the map's axes (x east, y up, z south).
// The linear radiance of each pixel is rendered once into a float framebuffer and kept for
// `window.engineDemo.linearAt(x, y)`; the canvas shows it through 1 - exp(-k L) and the sRGB
// curve. URL parameters: map, light, eye=x,y,z, target=x,y,z, fov (vertical, degrees),
// albedo, exposure (k; default 1 / the radiance of a white horizontal surface).
"use strict";

const params = new URLSearchParams(location.search);
let settings = null;

const readSettings = () => ({
  map: params.get("map") || "sky.hdr",
  light: params.get("light") || "light.json",
  eye: vectorParameter("eye", [3.9, 1.3, -3.4]),
  target: vectorParameter("target", [0.0, 0.4, 0.0]),
  fovDeg: Number(params.get("fov") || 50),
  albedo: Number(params.get("albedo") || 0.8),
  exposure: params.has("exposure") ? Number(params.get("exposure")) : null,
});

// Faces of each layout, (row, column) of their square; same as render.cube_map.CUBE_LAYOUTS.
const LAYOUTS = {
  cross: { across: 4, down: 3, faces: { "+Y": [0, 1], "-X": [1, 0], "+Z": [1, 1], "+X": [1, 2],
                                         "-Z": [1, 3], "-Y": [2, 1] } },
  strip: { across: 6, down: 1, faces: { "+X": [0, 0], "-X": [0, 1], "+Y": [0, 2],
                                         "-Y": [0, 3], "+Z": [0, 4], "-Z": [0, 5] } },
};

function vectorParameter(name, fallback) {
  if (!params.has(name)) return fallback;
  const values = params.get(name).split(",").map(Number);
  if (values.length !== 3 || values.some((v) => !Number.isFinite(v))) {
    throw new Error(`${name}=${params.get(name)} must be three numbers x,y,z`);
  }
  return values;
}

async function fetchOrFail(url) {
  const response = await fetch(url);
  if (!response.ok) throw new Error(`${url}: ${response.status} ${response.statusText}`);
  return response;
}

// A Radiance .hdr of flat RGBE scanlines -> {width, height, rgb: Float32Array, top row first}.
function decodeRadianceHdr(bytes, url) {
  let position = 0;
  const lines = [];
  for (;;) {
    const end = bytes.indexOf(10, position);
    if (end < 0) throw new Error(`${url}: no end of the Radiance header`);
    const line = String.fromCharCode(...bytes.subarray(position, end));
    position = end + 1;
    if (line === "") break;
    lines.push(line);
  }
  if (!lines[0].startsWith("#?")) throw new Error(`${url} is not a Radiance .hdr file`);
  if (!lines.includes("FORMAT=32-bit_rle_rgbe")) {
    throw new Error(`${url}: only FORMAT=32-bit_rle_rgbe (RGB) is read here`);
  }
  const end = bytes.indexOf(10, position);
  const size = String.fromCharCode(...bytes.subarray(position, end)).match(/^-Y (\d+) \+X (\d+)$/);
  if (!size) throw new Error(`${url}: only top-down images (-Y height +X width) are read here`);
  position = end + 1;
  const height = Number(size[1]);
  const width = Number(size[2]);
  if (bytes.length - position !== width * height * 4) {  // run-length encoded is shorter
    throw new Error(`${url}: only flat (not run-length encoded) scanlines are read here, ` +
                    "as skyscatter writes them");
  }
  const rgb = new Float32Array(width * height * 3);
  for (let k = 0; k < width * height; k++) {
    const e = bytes[position + 4 * k + 3];
    // v = (m + 0.5) / 256 * 2^(e - 128); e = 0 is black (render/radiance_hdr.py)
    const scale = e === 0 ? 0.0 : Math.pow(2.0, e - 136);
    for (let c = 0; c < 3; c++) {
      rgb[3 * k + c] = e === 0 ? 0.0 : (bytes[position + 4 * k + c] + 0.5) * scale;
    }
  }
  return { width, height, rgb };
}

function cubeFaces(image, url) {
  const name = image.width * 3 === image.height * 4 ? "cross"
    : image.width === image.height * 6 ? "strip" : null;
  if (name === null) {
    throw new Error(`${url} is ${image.width} x ${image.height}: a cube map cross is 4:3 and ` +
                    "a strip 6:1 (skyscatter render --camera cubemap)");
  }
  const layout = LAYOUTS[name];
  const side = image.width / layout.across;
  const faces = {};
  for (const [face, [row, column]] of Object.entries(layout.faces)) {
    const pixels = new Float32Array(side * side * 3);
    for (let y = 0; y < side; y++) {
      const start = ((row * side + y) * image.width + column * side) * 3;
      pixels.set(image.rgb.subarray(start, start + side * 3), y * side * 3);
    }
    faces[face] = pixels;
  }
  return { side, faces };
}

const VERTEX_SHADER = `#version 300 es
void main() {
  vec2 corner = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
  gl_Position = vec4(corner * 2.0 - 1.0, 0.0, 1.0);
}`;

const FRAGMENT_SHADER = `#version 300 es
precision highp float;
uniform samplerCube u_sky;
uniform vec3 u_eye, u_right, u_up, u_forward;
uniform vec2 u_half_extent;       // tan(fov / 2) * aspect, tan(fov / 2)
uniform vec2 u_viewport;
uniform vec3 u_sh[9];             // E_lm, lux, in the order of the light file
uniform vec3 u_sun_direction, u_sun_rgb;
uniform float u_albedo, u_exposure;
uniform bool u_display;
out vec4 colour;

// same as render.environment_light.sh_basis
vec3 irradiance(vec3 n) {
  return u_sh[0] * 0.282095
       + u_sh[1] * 0.488603 * n.y + u_sh[2] * 0.488603 * n.z + u_sh[3] * 0.488603 * n.x
       + u_sh[4] * 1.092548 * n.x * n.y + u_sh[5] * 1.092548 * n.y * n.z
       + u_sh[6] * 0.315392 * (3.0 * n.z * n.z - 1.0)
       + u_sh[7] * 1.092548 * n.x * n.z + u_sh[8] * 0.546274 * (n.x * n.x - n.y * n.y);
}

vec3 encode_srgb(vec3 v) {  // IEC 61966-2-1
  return mix(v * 12.92, 1.055 * pow(v, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, v));
}

void main() {
  vec2 ndc = gl_FragCoord.xy / u_viewport * 2.0 - 1.0;
  vec3 d = normalize(u_forward + ndc.x * u_half_extent.x * u_right
                     + ndc.y * u_half_extent.y * u_up);
  // the unit sphere at the origin
  float b = dot(u_eye, d);
  float disc = b * b - dot(u_eye, u_eye) + 1.0;
  float t = disc >= 0.0 ? -b - sqrt(disc) : -1.0;
  vec3 radiance;
  if (t > 0.0) {
    vec3 n = normalize(u_eye + t * d);
    vec3 e = max(irradiance(n), 0.0) + u_sun_rgb * max(dot(n, u_sun_direction), 0.0);
    radiance = u_albedo / 3.14159265358979 * e;
  } else {
    radiance = texture(u_sky, d).rgb;
  }
  colour = vec4(u_display ? encode_srgb(1.0 - exp(-u_exposure * radiance)) : radiance, 1.0);
}`;

function compile(gl, type, source) {
  const shader = gl.createShader(type);
  gl.shaderSource(shader, source);
  gl.compileShader(shader);
  if (!gl.getShaderParameter(shader, gl.COMPILE_STATUS)) {
    throw new Error(gl.getShaderInfoLog(shader));
  }
  return shader;
}

function program(gl) {
  const p = gl.createProgram();
  gl.attachShader(p, compile(gl, gl.VERTEX_SHADER, VERTEX_SHADER));
  gl.attachShader(p, compile(gl, gl.FRAGMENT_SHADER, FRAGMENT_SHADER));
  gl.linkProgram(p);
  if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(p));
  return p;
}

function cubeTexture(gl, cube) {
  const filterable = gl.getExtension("OES_texture_float_linear") !== null;
  const texture = gl.createTexture();
  gl.bindTexture(gl.TEXTURE_CUBE_MAP, texture);
  const targets = { "+X": gl.TEXTURE_CUBE_MAP_POSITIVE_X, "-X": gl.TEXTURE_CUBE_MAP_NEGATIVE_X,
                    "+Y": gl.TEXTURE_CUBE_MAP_POSITIVE_Y, "-Y": gl.TEXTURE_CUBE_MAP_NEGATIVE_Y,
                    "+Z": gl.TEXTURE_CUBE_MAP_POSITIVE_Z, "-Z": gl.TEXTURE_CUBE_MAP_NEGATIVE_Z };
  for (const [face, pixels] of Object.entries(cube.faces)) {
    gl.texImage2D(targets[face], 0, gl.RGB32F, cube.side, cube.side, 0, gl.RGB, gl.FLOAT,
                  pixels);
  }
  const filter = filterable ? gl.LINEAR : gl.NEAREST;
  gl.texParameteri(gl.TEXTURE_CUBE_MAP, gl.TEXTURE_MIN_FILTER, filter);
  gl.texParameteri(gl.TEXTURE_CUBE_MAP, gl.TEXTURE_MAG_FILTER, filter);
  return texture;
}

const subtract = (a, b) => a.map((v, i) => v - b[i]);
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                         a[0] * b[1] - a[1] * b[0]];
const normalise = (a) => { const n = Math.hypot(...a); return a.map((v) => v / n); };

function setUniforms(gl, p, light, width, height) {
  const forward = normalise(subtract(settings.target, settings.eye));
  const right = normalise(cross(forward, [0, 1, 0]));
  const up = cross(right, forward);
  const tanHalf = Math.tan(settings.fovDeg * Math.PI / 360);
  const u = (name) => gl.getUniformLocation(p, name);
  gl.uniform3fv(u("u_eye"), settings.eye);
  gl.uniform3fv(u("u_right"), right);
  gl.uniform3fv(u("u_up"), up);
  gl.uniform3fv(u("u_forward"), forward);
  gl.uniform2f(u("u_half_extent"), tanHalf * width / height, tanHalf);
  gl.uniform2f(u("u_viewport"), width, height);
  gl.uniform3fv(u("u_sh"), light.sh_irradiance.rgb.flat());
  const sun = light.sun || { direction: [0, 1, 0], rgb: [0, 0, 0] };
  gl.uniform3fv(u("u_sun_direction"), sun.direction);
  gl.uniform3fv(u("u_sun_rgb"), sun.rgb);
  gl.uniform1f(u("u_albedo"), settings.albedo);
  // default exposure: a white horizontal surface's radiance (Rec. 709 luminance) maps to 1
  const white = [0, 1, 2].map((c) => (light.sh_irradiance.rgb[0][c] * 0.282095
    + light.sh_irradiance.rgb[1][c] * 0.488603 - light.sh_irradiance.rgb[6][c] * 0.315392
    - light.sh_irradiance.rgb[8][c] * 0.546274
    + sun.rgb[c] * Math.max(sun.direction[1], 0)) / Math.PI);
  const key = 0.2126 * white[0] + 0.7152 * white[1] + 0.0722 * white[2];
  gl.uniform1f(u("u_exposure"), settings.exposure ?? 1.0 / key);
  gl.uniform1i(u("u_sky"), 0);
}

async function main() {
  settings = readSettings();
  const [hdr, light] = await Promise.all([
    fetchOrFail(settings.map).then((r) => r.arrayBuffer()),
    fetchOrFail(settings.light).then((r) => r.json())]);
  const cube = cubeFaces(decodeRadianceHdr(new Uint8Array(hdr), settings.map), settings.map);
  const canvas = document.getElementById("view");
  const gl = canvas.getContext("webgl2");
  if (!gl) throw new Error("this browser has no WebGL2");
  if (!gl.getExtension("EXT_color_buffer_float")) {
    throw new Error("this browser cannot render to float textures (EXT_color_buffer_float)");
  }
  const p = program(gl);
  gl.useProgram(p);
  gl.bindVertexArray(gl.createVertexArray());
  gl.activeTexture(gl.TEXTURE0);
  cubeTexture(gl, cube);
  const { width, height } = canvas;
  setUniforms(gl, p, light, width, height);

  // the linear radiance, kept for linearAt
  const target = gl.createTexture();
  gl.bindTexture(gl.TEXTURE_2D, target);
  gl.texStorage2D(gl.TEXTURE_2D, 1, gl.RGBA32F, width, height);
  const framebuffer = gl.createFramebuffer();
  gl.bindFramebuffer(gl.FRAMEBUFFER, framebuffer);
  gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, target, 0);
  gl.viewport(0, 0, width, height);
  gl.uniform1i(gl.getUniformLocation(p, "u_display"), 0);
  gl.drawArrays(gl.TRIANGLES, 0, 3);
  const linear = new Float32Array(width * height * 4);
  gl.readPixels(0, 0, width, height, gl.RGBA, gl.FLOAT, linear);

  gl.bindFramebuffer(gl.FRAMEBUFFER, null);
  gl.uniform1i(gl.getUniformLocation(p, "u_display"), 1);
  gl.drawArrays(gl.TRIANGLES, 0, 3);

  window.engineDemo = {
    // linear RGB [cd m^-2] of the pixel x across, y down from the top row
    linearAt(x, y) {
      const k = ((height - 1 - y) * width + x) * 4;
      return [linear[k], linear[k + 1], linear[k + 2]];
    },
  };
  document.body.dataset.ready = "1";
}

main().catch((error) => {
  const box = document.getElementById("error");
  box.textContent = String(error.message || error);
  box.hidden = false;
  document.body.dataset.ready = "error";
});
