// The fast model on the GPU (shaders/fast_model.glsl; S. Hillaire, EGSR 2020,
// doi:10.1111/cgf.14050): the transmittance and multiple-scattering LUTs made again from the
// atmosphere's description (viewer/gpu_fast.py) whenever a physical parameter changes (and
// our LUT of the sky's irradiance on the ground), the
// sky-view LUT whenever the camera's altitude or the sun moves; one pass per LUT and group of
// four wavelengths, into a layer of an RGBA16F texture array (needs EXT_color_buffer_float).

import {floatTexture} from "./tables.js";

const UNITS = {u_fast_transmittance: 0, u_fast_multiple: 1, u_fast_sky_view: 2,
               u_fast_density: 3, u_fast_phase: 4, u_fast_irradiance: 5};
const LUTS = ["transmittance", "multiple", "irradiance", "sky_view"];

export class FastModel {
  // `viewer`: its gl, programs, uniform locations and full-screen triangle; `decoded`: the
  // description (tables.js decodeFast)
  constructor(viewer, decoded) {
    const gl = viewer.gl;
    this.viewer = viewer;
    this.header = decoded.header;
    const h = this.header;
    this.groups = h.groups;
    const [densityRows, densityRow] = decoded.arrays.density.shape;
    this.constituents = h.names.length;
    this.textures = {
      u_fast_density: floatTexture(gl, gl.R32F, gl.RED, densityRow, densityRows, decoded.arrays.density.data),
      u_fast_phase: floatTexture(gl, gl.RGBA32F, gl.RGBA, decoded.arrays.phase.shape[1],
                                decoded.arrays.phase.shape[0], decoded.arrays.phase.data),
    };
    this.framebuffers = {};
    for (const lut of LUTS) {
      const [width, height] = viewer.layout.fast.sizes[lut];
      const texture = gl.createTexture();
      gl.bindTexture(gl.TEXTURE_2D_ARRAY, texture);
      gl.texStorage3D(gl.TEXTURE_2D_ARRAY, 1, gl.RGBA16F, width, height, this.groups);
      for (const [key, value] of [[gl.TEXTURE_MIN_FILTER, gl.LINEAR], [gl.TEXTURE_MAG_FILTER, gl.LINEAR],
                                  [gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE], [gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE]]) {
        gl.texParameteri(gl.TEXTURE_2D_ARRAY, key, value);
      }
      this.textures[`u_fast_${lut}`] = texture;
      this.framebuffers[lut] = Array.from({length: this.groups}, (_, g) => {
        const framebuffer = gl.createFramebuffer();
        gl.bindFramebuffer(gl.FRAMEBUFFER, framebuffer);
        gl.framebufferTextureLayer(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, texture, 0, g);
        return framebuffer;
      });
    }
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    // XYZ of each group: mat4x3 columns C_w E_w (the LUTs are per unit irradiance)
    this.toXyz = new Float32Array(12 * viewer.layout.fast.max_groups);
    h.xyz_weights.forEach((row, w) => {
      row.forEach((value, c) => { this.toXyz[3 * w + c] = value * h.sun_irradiance[w]; });
    });
    this.version = 0;
    this.viewKey = null;
  }

  delete() {
    const gl = this.viewer.gl;
    Object.values(this.textures).forEach((t) => gl.deleteTexture(t));
    Object.values(this.framebuffers).flat().forEach((f) => gl.deleteFramebuffer(f));
  }

  // The uniforms of every fast program: each group's coefficients (each constituent's times
  // its factor in this.amounts) and ground albedo (this.albedo, or the description's spectral
  // one when null)
  uniforms() {
    const h = this.header;
    const {max_constituents: max, max_groups: groups} = this.viewer.layout.fast;
    const extinction = new Float32Array(4 * max * groups);
    const scattering = new Float32Array(4 * max * groups);
    const albedo = new Float32Array(4 * groups);
    for (let g = 0; g < this.groups; ++g) {
      h.names.forEach((name, c) => {
        const factor = this.amounts[name] ?? 1;
        for (let k = 0; k < 4; ++k) {
          extinction[4 * (g * max + c) + k] = factor * h.extinction_m[c][4 * g + k];
          scattering[4 * (g * max + c) + k] = factor * h.scattering_m[c][4 * g + k];
        }
      });
      for (let k = 0; k < 4; ++k) albedo[4 * g + k] = this.albedo ?? h.ground_albedo[4 * g + k];
    }
    return {extinction, scattering, albedo};
  }

  // Binds the LUTs and data (those not in `writing`) and sets the uniforms for `program`
  bind(program, group, writing = null) {
    const gl = this.viewer.gl;
    for (const [name, unit] of Object.entries(UNITS)) {
      gl.activeTexture(gl.TEXTURE0 + unit);
      const array = name !== "u_fast_density" && name !== "u_fast_phase";
      gl.bindTexture(array ? gl.TEXTURE_2D_ARRAY : gl.TEXTURE_2D, name === writing ? null : this.textures[name]);
      const location = this.viewer.uniform(program, name);
      if (location !== null) gl.uniform1i(location, unit);
    }
    const h = this.header;
    const set = (name, setter, ...values) => {
      const location = this.viewer.uniform(program, name);
      if (location !== null) gl[setter](location, ...values);
    };
    const u = this.uniforms();
    set("u_fast_extinction", "uniform4fv", u.extinction);
    set("u_fast_scattering", "uniform4fv", u.scattering);
    set("u_fast_albedo", "uniform4fv", u.albedo);
    set("u_fast_group", "uniform1i", group);
    set("u_fast_groups", "uniform1i", this.groups);
    set("u_fast_constituents", "uniform1i", this.constituents);
    set("u_fast_altitudes", "uniform1i", h.altitudes);
    set("u_fast_density_rows", "uniform1i", h.density_rows);
    set("u_fast_altitude_step", "uniform1f", h.altitude_step_m);
    set("u_fast_to_xyz", "uniformMatrix4x3fv", false, this.toXyz);
    set("u_bottom_radius", "uniform1f", h.bottom_radius_m);
    set("u_top_radius", "uniform1f", h.top_radius_m);
    set("u_fast_mu_s_centre", "uniform1f", h.multiple_scattering_mu_s_centre);
    set("u_sun_irradiance", "uniform3fv", h.sun_irradiance_xyz);
    set("u_sun_angular_radius", "uniform1f", h.sun_angular_radius_rad);
    set("u_sun_solid_angle", "uniform1f", h.sun_solid_angle_sr);
    set("u_sun_disk", "uniform3fv", h.sun_disk_xyz.flat());
  }

  // One LUT pass per group into `lut` with program `program`, then `extra` uniforms
  pass(lut, program, extra = {}) {
    const gl = this.viewer.gl;
    const [width, height] = this.viewer.layout.fast.sizes[lut];
    gl.useProgram(this.viewer.programs[program]);
    gl.viewport(0, 0, width, height);
    gl.bindVertexArray(this.viewer.fullScreen);
    for (let g = 0; g < this.groups; ++g) {
      gl.bindFramebuffer(gl.FRAMEBUFFER, this.framebuffers[lut][g]);
      this.bind(program, g, `u_fast_${lut}`);
      for (const [name, value] of Object.entries(extra)) {
        gl.uniform1f(this.viewer.uniform(program, name), value);
      }
      gl.drawArrays(gl.TRIANGLES, 0, 3);
    }
  }

  // The transmittance and multiple-scattering LUTs for the constituents' factors `amounts`
  // ({name: factor}) and the ground albedo (null: the atmosphere's)
  compute(amounts, albedo) {
    const gl = this.viewer.gl;
    const previous = gl.getParameter(gl.FRAMEBUFFER_BINDING);
    this.amounts = {...amounts};
    this.albedo = albedo;
    this.pass("transmittance", "fast_transmittance");
    this.pass("multiple", "fast_multiple");
    this.pass("irradiance", "fast_irradiance");
    gl.bindFramebuffer(gl.FRAMEBUFFER, previous);
    this.version += 1;
    this.viewKey = null;
  }

  // The sky-view LUT for a camera at `position` (world [m]) and the sun towards `sun`, made
  // again only when the camera's radius, the sun's cosine there or the LUTs changed; none
  // from space (the final pass marches per pixel there)
  skyView(position, sun) {
    const h = this.header;
    const length = Math.hypot(...position);
    if (length > h.top_radius_m) return;
    const r = Math.min(Math.max(length, h.bottom_radius_m), h.top_radius_m);
    const muS = position.reduce((sum, v, i) => sum + v * sun[i], 0) / length;
    const key = JSON.stringify([r, muS, this.version]);
    if (key === this.viewKey) return;
    const gl = this.viewer.gl;
    const previous = gl.getParameter(gl.FRAMEBUFFER_BINDING);
    this.pass("sky_view", "fast_sky_view", {u_fast_view_radius: r, u_fast_view_mu_s: muS});
    gl.bindFramebuffer(gl.FRAMEBUFFER, previous);
    this.viewKey = key;
  }

  // Group g of a LUT as a Float32Array (w x h x 4), for tests and the benchmark
  read(lut, g) {
    const gl = this.viewer.gl;
    const [width, height] = this.viewer.layout.fast.sizes[lut];
    const previous = gl.getParameter(gl.FRAMEBUFFER_BINDING);
    gl.bindFramebuffer(gl.FRAMEBUFFER, this.framebuffers[lut][g]);
    const pixels = new Float32Array(width * height * 4);
    gl.readPixels(0, 0, width, height, gl.RGBA, gl.FLOAT, pixels);
    gl.bindFramebuffer(gl.FRAMEBUFFER, previous);
    return pixels;
  }
}
