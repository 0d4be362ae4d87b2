// Evaluates the viewer's GLSL parameterisations (static/shaders/parameterisation.glsl) in the
// browser's WebGL2 on a list of inputs and returns the results (test_viewer_browser.py).
// Called by Playwright's page.evaluate with {inputs: [[r, mu, mu_s, nu], ...], radii: [R_b, R_t],
// mu_s_min, sun_angle_share, sizes: [n_r, n_mu, n_mu_s], radius_warp: [...],
// radius_warp_identity: bool (the header's flag: the shader then skips the warp)}; returns
// {name: [values...]} per output.
async ({inputs, radii, mu_s_min, sun_angle_share, sizes, radius_warp, radius_warp_identity}) => {
  const canvas = document.createElement("canvas");
  const gl = canvas.getContext("webgl2");
  if (!gl.getExtension("EXT_color_buffer_float")) throw new Error("no EXT_color_buffer_float");
  const text = async (name) => (await fetch(`static/${name}`)).text();
  const library = (await text("generated/constants.glsl")) + (await text("shaders/parameterisation.glsl"));
  const n = inputs.length;
  const width = 64;
  const height = Math.ceil(n / width);
  const data = new Float32Array(width * height * 4);
  inputs.forEach((row, i) => data.set(row, 4 * i));
  const input = gl.createTexture();
  gl.bindTexture(gl.TEXTURE_2D, input);
  gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA32F, width, height, 0, gl.RGBA, gl.FLOAT, data);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
  const outputs = {
    scattering_uvwz: `vec4(scattering_u_r(r, R_b, R_t, N_R),
        scattering_u_mu(r, mu, ray_intersects_ground(r, mu, R_b), R_b, R_t, N_MU),
        scattering_u_mu_s(mu_s, R_b, R_t, MU_S_MIN, SUN_ANGLE_SHARE, N_MU_S), scattering_u_nu(nu, mu, mu_s))`,
    transmittance_irradiance: `vec4(transmittance_x_from_r_mu(r, mu, R_b, R_t),
        irradiance_x_from_r_mu_s(r, mu_s, R_b, R_t))`,
    transmittance_inverse: `vec4(transmittance_r_mu_from_x(0.5 * (nu + 1.0), 0.5 * (mu_s + 1.0), R_b, R_t)
        - vec2(R_b, 0.0), 0.0, 0.0)`,
    distances: `vec4(distance_to_top_boundary(r, mu, R_t),
        ray_intersects_ground(r, mu, R_b) ? distance_to_bottom_boundary(r, mu, R_b) : -1.0,
        ray_intersects_ground(r, mu, R_b) ? 1.0 : 0.0,
        texture_coord_from_unit_range(0.5 * (mu + 1.0), N_MU))`,
  };
  const vertex = `#version 300 es
in vec2 position; void main() { gl_Position = vec4(position, 0.0, 1.0); }`;
  const buffer = gl.createBuffer();
  gl.bindBuffer(gl.ARRAY_BUFFER, buffer);
  gl.bufferData(gl.ARRAY_BUFFER, new Float32Array([-1, -1, 3, -1, -1, 3]), gl.STATIC_DRAW);
  const target = gl.createTexture();
  gl.bindTexture(gl.TEXTURE_2D, target);
  gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA32F, width, height, 0, gl.RGBA, gl.FLOAT, null);
  const framebuffer = gl.createFramebuffer();
  gl.bindFramebuffer(gl.FRAMEBUFFER, framebuffer);
  gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, target, 0);
  const results = {};
  for (const [name, expression] of Object.entries(outputs)) {
    const fragment = `#version 300 es
precision highp float; precision highp int;
${library}
uniform sampler2D inputs;
const float R_b = ${radii[0].toFixed(3)}; const float R_t = ${radii[1].toFixed(3)};
const float MU_S_MIN = ${mu_s_min.toFixed(9)};
const float SUN_ANGLE_SHARE = ${sun_angle_share.toFixed(9)};
const float N_R = ${sizes[0].toFixed(1)}; const float N_MU = ${sizes[1].toFixed(1)};
const float N_MU_S = ${sizes[2].toFixed(1)};
out vec4 result;
void main() {
  vec4 x = texelFetch(inputs, ivec2(gl_FragCoord.xy), 0);
  float r = x.x; float mu = x.y; float mu_s = x.z; float nu = x.w;
  result = ${expression};
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
    gl.useProgram(program);
    gl.enableVertexAttribArray(0);
    gl.vertexAttribPointer(0, 2, gl.FLOAT, false, 0, 0);
    gl.activeTexture(gl.TEXTURE0);
    gl.bindTexture(gl.TEXTURE_2D, input);
    gl.uniform1i(gl.getUniformLocation(program, "inputs"), 0);
    const warp = new Float32Array(4 * Math.ceil(radius_warp.length / 4));
    warp.set(radius_warp);
    gl.uniform4fv(gl.getUniformLocation(program, "u_radius_warp"), warp);
    gl.uniform1i(gl.getUniformLocation(program, "u_radius_warp_identity"),
                 radius_warp_identity ? 1 : 0);
    gl.viewport(0, 0, width, height);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
    const pixels = new Float32Array(width * height * 4);
    gl.readPixels(0, 0, width, height, gl.RGBA, gl.FLOAT, pixels);
    results[name] = Array.from(pixels.slice(0, 4 * n));
  }
  return results;
}
