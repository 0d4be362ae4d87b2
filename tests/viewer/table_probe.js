// Renders sky radiance from exported tables through the exported GLSL snippet (the folder of
// `skyscatter export-tables --format ktx2 --precision half`) in the browser's WebGL2
// (test_table_export_browser.py). Called by Playwright's page.evaluate with {glsl: the
// snippet's text, uniforms: the sidecar's "uniforms", textures: {name: {data: base64 of the
// KTX2 level's float16 RGBA texels, width, height, depth}}, directions: [[x, y, z, valid] per
// pixel, row 0 first], width, height, origin: [x, y, z] m, sun: [x, y, z]}; returns the
// radiance [r, g, b, a] per pixel, row 0 first.
async ({glsl, uniforms, textures, directions, width, height, origin, sun}) => {
  const canvas = document.createElement("canvas");
  const gl = canvas.getContext("webgl2");
  if (!gl.getExtension("EXT_color_buffer_float")) throw new Error("no EXT_color_buffer_float");
  const halves = (text) => {
    const bytes = Uint8Array.from(atob(text), (c) => c.charCodeAt(0));
    return new Uint16Array(bytes.buffer);
  };
  const vertex = `#version 300 es
in vec2 position; void main() { gl_Position = vec4(position, 0.0, 1.0); }`;
  const fragment = `#version 300 es
precision highp float; precision highp int; precision highp sampler3D;
${glsl}
uniform sampler2D u_directions;
uniform vec3 u_origin;
uniform vec3 u_sun;
out vec4 result;
void main() {
  vec4 d = texelFetch(u_directions, ivec2(gl_FragCoord.xy), 0);
  result = d.w > 0.5 ? vec4(sky_radiance(u_origin, d.xyz, u_sun, 1.0), 1.0) : vec4(0.0);
}`;
  const program = gl.createProgram();
  for (const [type, source] of [[gl.VERTEX_SHADER, vertex], [gl.FRAGMENT_SHADER, fragment]]) {
    const shader = gl.createShader(type);
    gl.shaderSource(shader, source);
    gl.compileShader(shader);
    if (!gl.getShaderParameter(shader, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(shader));
    gl.attachShader(program, shader);
  }
  gl.bindAttribLocation(program, 0, "position");
  gl.linkProgram(program);
  if (!gl.getProgramParameter(program, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(program));
  gl.useProgram(program);
  // the tables: RGBA16F as the KTX2 files hold them, linear filtering (the phase texture is
  // read with texelFetch), clamped to the edge
  const units = {u_transmittance: 0, u_irradiance: 1, u_scattering: 2, u_phase: 3};
  for (const [name, unit] of Object.entries(units)) {
    const table = textures[name.slice(2)];
    const target = table.depth ? gl.TEXTURE_3D : gl.TEXTURE_2D;
    const texture = gl.createTexture();
    gl.activeTexture(gl.TEXTURE0 + unit);
    gl.bindTexture(target, texture);
    gl.pixelStorei(gl.UNPACK_ALIGNMENT, 1);
    if (table.depth) {
      gl.texImage3D(target, 0, gl.RGBA16F, table.width, table.height, table.depth, 0, gl.RGBA,
                    gl.HALF_FLOAT, halves(table.data));
    } else {
      gl.texImage2D(target, 0, gl.RGBA16F, table.width, table.height, 0, gl.RGBA,
                    gl.HALF_FLOAT, halves(table.data));
    }
    const filter = name === "u_phase" ? gl.NEAREST : gl.LINEAR;
    gl.texParameteri(target, gl.TEXTURE_MIN_FILTER, filter);
    gl.texParameteri(target, gl.TEXTURE_MAG_FILTER, filter);
    for (const wrap of [gl.TEXTURE_WRAP_S, gl.TEXTURE_WRAP_T, gl.TEXTURE_WRAP_R]) {
      gl.texParameteri(target, wrap, gl.CLAMP_TO_EDGE);
    }
    gl.uniform1i(gl.getUniformLocation(program, name), unit);
  }
  // every other uniform from the sidecar, by the type the shader declares
  const count = gl.getProgramParameter(program, gl.ACTIVE_UNIFORMS);
  for (let i = 0; i < count; ++i) {
    const info = gl.getActiveUniform(program, i);
    const name = info.name.replace("[0]", "");
    if (!(name in uniforms)) continue;
    const location = gl.getUniformLocation(program, info.name);
    const value = [].concat(uniforms[name]);
    const setters = {[gl.FLOAT]: "uniform1fv", [gl.FLOAT_VEC2]: "uniform2fv",
                     [gl.FLOAT_VEC3]: "uniform3fv", [gl.FLOAT_VEC4]: "uniform4fv",
                     [gl.INT]: "uniform1iv"};
    if (!(info.type in setters)) throw new Error(`no setter for ${name}`);
    const array = info.type === gl.INT ? new Int32Array(value) : new Float32Array(value);
    gl[setters[info.type]](location, array);
  }
  const directionTexture = gl.createTexture();
  gl.activeTexture(gl.TEXTURE4);
  gl.bindTexture(gl.TEXTURE_2D, directionTexture);
  gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA32F, width, height, 0, gl.RGBA, gl.FLOAT,
                new Float32Array(directions.flat()));
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
  gl.uniform1i(gl.getUniformLocation(program, "u_directions"), 4);
  gl.uniform3fv(gl.getUniformLocation(program, "u_origin"), new Float32Array(origin));
  gl.uniform3fv(gl.getUniformLocation(program, "u_sun"), new Float32Array(sun));
  const buffer = gl.createBuffer();
  gl.bindBuffer(gl.ARRAY_BUFFER, buffer);
  gl.bufferData(gl.ARRAY_BUFFER, new Float32Array([-1, -1, 3, -1, -1, 3]), gl.STATIC_DRAW);
  gl.enableVertexAttribArray(0);
  gl.vertexAttribPointer(0, 2, gl.FLOAT, false, 0, 0);
  const target = gl.createTexture();
  gl.activeTexture(gl.TEXTURE5);
  gl.bindTexture(gl.TEXTURE_2D, target);
  gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA32F, width, height, 0, gl.RGBA, gl.FLOAT, null);
  const framebuffer = gl.createFramebuffer();
  gl.bindFramebuffer(gl.FRAMEBUFFER, framebuffer);
  gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, target, 0);
  gl.viewport(0, 0, width, height);
  gl.drawArrays(gl.TRIANGLES, 0, 3);
  const pixels = new Float32Array(width * height * 4);
  gl.readPixels(0, 0, width, height, gl.RGBA, gl.FLOAT, pixels);
  return Array.from(pixels);
}
