// Decodes the table message of viewer/gpu_tables.py (layout: generated/lut_layout.json) and
// uploads it as WebGL2 textures: RGB16F, linear filtering for the tables the hardware
// interpolates, nearest for those read with texelFetch.

export async function fetchLayout() {
  const response = await fetch("static/generated/lut_layout.json");
  return response.json();
}

// {header, arrays: {name: {shape, data: Uint16Array}}} from an ArrayBuffer
export function decodeTables(buffer, layout) {
  return unpackMessage(buffer, layout.magic, layout.format_version, "table");
}

// {header, arrays: {name: {shape, data: Float32Array}}} of the fast model's description
// (viewer/gpu_fast.py)
export function decodeFast(buffer, layout) {
  return unpackMessage(buffer, layout.fast.magic, layout.fast.format_version, "fast model");
}

// {header, arrays: {name: {shape, data}}} of a binary message (viewer/gpu_tables.py
// unpack_message): magic, version and header length, the JSON header, then the arrays at its
// offsets, float16 as Uint16Array unless the entry's dtype says float32
function unpackMessage(buffer, magicExpected, formatVersion, what) {
  const bytes = new Uint8Array(buffer);
  const magic = String.fromCharCode(...bytes.slice(0, 4));
  if (magic !== magicExpected) throw new Error(`the server sent something that is not a ${what} message`);
  const view = new DataView(buffer);
  const version = view.getUint32(4, true);
  if (version !== formatVersion) {
    throw new Error(`${what} message version ${version}; this page reads ${formatVersion}: reload it`);
  }
  const length = view.getUint32(8, true);
  const header = JSON.parse(new TextDecoder().decode(bytes.slice(12, 12 + length)));
  const start = 12 + length;
  const arrays = {};
  for (const [name, entry] of Object.entries(header.arrays)) {
    const count = entry.shape.reduce((x, y) => x * y, 1);
    const Type = entry.dtype === "float32" ? Float32Array : Uint16Array;
    arrays[name] = {shape: entry.shape, data: new Type(buffer, start + entry.offset, count)};
  }
  return {header, arrays};
}

function texture2d(gl, width, height, data, filter) {
  const texture = gl.createTexture();
  gl.bindTexture(gl.TEXTURE_2D, texture);
  gl.pixelStorei(gl.UNPACK_ALIGNMENT, 1);
  gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGB16F, width, height, 0, gl.RGB, gl.HALF_FLOAT, data);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, filter);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, filter);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE);
  return texture;
}

// The textures and uniforms of decoded tables; the old ones are deleted by `deleteTables`
export function uploadTables(gl, decoded) {
  const {header, arrays} = decoded;
  const [nR, nMu, nMuS, nNu, nT] = header.scattering_shape;
  const transmittance = arrays.transmittance.shape;
  const irradiance = arrays.irradiance.shape;
  const phase = arrays.phase.shape;
  const scattering = gl.createTexture();
  gl.bindTexture(gl.TEXTURE_3D, scattering);
  gl.pixelStorei(gl.UNPACK_ALIGNMENT, 1);
  gl.texImage3D(gl.TEXTURE_3D, 0, gl.RGB16F, nNu * nMuS, nMu, nT * nR, 0, gl.RGB, gl.HALF_FLOAT,
                arrays.scattering.data);
  for (const [key, value] of [[gl.TEXTURE_MIN_FILTER, gl.LINEAR], [gl.TEXTURE_MAG_FILTER, gl.LINEAR],
                              [gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE], [gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE],
                              [gl.TEXTURE_WRAP_R, gl.CLAMP_TO_EDGE]]) {
    gl.texParameteri(gl.TEXTURE_3D, key, value);
  }
  return {
    header,
    textures: {
      transmittance: texture2d(gl, transmittance[1], transmittance[0], arrays.transmittance.data, gl.LINEAR),
      irradiance: texture2d(gl, irradiance[1], irradiance[0], arrays.irradiance.data, gl.LINEAR),
      phase: texture2d(gl, phase[1], phase[0], arrays.phase.data, gl.NEAREST),
      scattering,
    },
    uniforms: {
      u_transmittance_size: [transmittance[1], transmittance[0]],
      u_irradiance_size: [irradiance[1], irradiance[0]],
      u_scattering_shape: [nR, nMu, nMuS, nNu],
      u_n_tables: nT,
      u_n_single: header.scattering_names.length,
      u_phase_angles: header.phase_angles,
      u_phase_rows: header.phase_rows,
      u_transmittance_scale: header.scales.transmittance,
      u_irradiance_scale: header.scales.irradiance,
      u_phase_scale: header.scales.phase,
      u_scattering_scales: header.scales.scattering,
      u_bottom_radius: header.bottom_radius_m,
      u_top_radius: header.top_radius_m,
      u_mu_s_min: header.mu_s_min,
      u_sun_angle_share: header.sun_angle_share,
      u_radius_warp: paddedToVec4s(header.radius_warp),
      u_radius_warp_identity: header.radius_warp_identity ? 1 : 0,
      u_ground_albedo: header.ground_albedo_xyz,
      u_sun_irradiance: header.sun_irradiance_xyz,
      u_sun_angular_radius: header.sun_angular_radius_rad,
      u_sun_solid_angle: header.sun_solid_angle_sr,
      u_sun_disk: header.sun_disk_xyz.flat(),
    },
  };
}

// the values of `list` followed by zeros up to a whole number of vec4s
function paddedToVec4s(list) {
  const padded = new Float32Array(4 * Math.ceil(list.length / 4));
  padded.set(list);
  return padded;
}

export function deleteTables(gl, tables) {
  if (!tables) return;
  for (const texture of Object.values(tables.textures)) gl.deleteTexture(texture);
}

// {header, arrays: {name: {shape, data}}} of a cloud message (viewer/gpu_clouds.py: float16
// noise as Uint16Array, the rest Float32Array)
export function decodeClouds(buffer, layout) {
  return unpackMessage(buffer, layout.clouds.magic, layout.clouds.format_version, "cloud");
}

// A float texture of `data`, sampled texel by texel (no filtering)
export function floatTexture(gl, internal, format, width, height, data) {
  const texture = gl.createTexture();
  gl.bindTexture(gl.TEXTURE_2D, texture);
  gl.pixelStorei(gl.UNPACK_ALIGNMENT, 1);
  gl.texImage2D(gl.TEXTURE_2D, 0, internal, width, height, 0, format, gl.FLOAT, data);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
  return texture;
}

// The textures of decoded clouds (or of none: 1-texel stand-ins, so that every sampler of the
// sky program has a texture of its own type); `params` (n_layers rows of CLOUD_N_PARAMS) go to
// the shader as uniforms, with the wind's columns filled in (viewer.js `cloudUniforms`)
export function uploadClouds(gl, decoded) {
  const none = decoded === null;
  const header = none ? {n_layers: 0, texture_size: 1} : decoded.header;
  const layers = Math.max(header.n_layers, 1);
  const noise = gl.createTexture();
  gl.bindTexture(gl.TEXTURE_3D, noise);
  gl.pixelStorei(gl.UNPACK_ALIGNMENT, 1);
  if (none) {
    gl.texImage3D(gl.TEXTURE_3D, 0, gl.RG16F, 1, 1, 1, 0, gl.RG, gl.HALF_FLOAT, new Uint16Array(2));
  } else {
    const [depth, height, width] = decoded.arrays.noise.shape;
    gl.texImage3D(gl.TEXTURE_3D, 0, gl.RG16F, width, height, depth, 0, gl.RG, gl.HALF_FLOAT,
                  decoded.arrays.noise.data);
  }
  for (const [key, value] of [[gl.TEXTURE_MIN_FILTER, gl.LINEAR], [gl.TEXTURE_MAG_FILTER, gl.LINEAR],
                              [gl.TEXTURE_WRAP_S, gl.REPEAT], [gl.TEXTURE_WRAP_T, gl.REPEAT],
                              [gl.TEXTURE_WRAP_R, gl.CLAMP_TO_EDGE]]) {
    gl.texParameteri(gl.TEXTURE_3D, key, value);
  }
  const params = none ? new Float32Array(1) : decoded.arrays.params.data;
  const profileRows = none ? 1 : decoded.arrays.profiles.shape[1];
  const optics = new Float32Array(layers * 9);
  for (let layer = 0; layer < header.n_layers; ++layer) {
    ["mass_extinction_xyz_m2_g", "single_scattering_albedo_xyz", "asymmetry_xyz"].forEach((key, i) => {
      optics.set(header[key][layer], layer * 9 + i * 3);
    });
  }
  const angles = none ? 1 : decoded.arrays.phase.shape[1];
  return {
    header,
    params,
    textures: {
      noise,
      profiles: floatTexture(gl, gl.RG32F, gl.RG, profileRows, layers,
                             none ? new Float32Array(2) : decoded.arrays.profiles.data),
      phase: floatTexture(gl, gl.RGB32F, gl.RGB, angles, layers,
                          none ? new Float32Array(3) : decoded.arrays.phase.data),
      optics: floatTexture(gl, gl.RGB32F, gl.RGB, 3, layers, optics),
    },
  };
}

export function deleteClouds(gl, clouds) {
  if (!clouds) return;
  for (const texture of Object.values(clouds.textures)) gl.deleteTexture(texture);
}
