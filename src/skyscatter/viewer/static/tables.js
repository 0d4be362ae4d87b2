// Decodes the table message of viewer/gpu_tables.py (layout: generated/lut_layout.json) and
// uploads it as WebGL2 textures: RGB16F, linear filtering for the tables the hardware
// interpolates, nearest for those read with texelFetch.

export async function fetchLayout() {
  const response = await fetch("static/generated/lut_layout.json");
  return response.json();
}

// {header, arrays: {name: {shape, data: Uint16Array}}} from an ArrayBuffer
export function decodeTables(buffer, layout) {
  const bytes = new Uint8Array(buffer);
  const magic = String.fromCharCode(...bytes.slice(0, 4));
  if (magic !== layout.magic) throw new Error("the server sent something that is not a table message");
  const view = new DataView(buffer);
  const version = view.getUint32(4, true);
  if (version !== layout.format_version) {
    throw new Error(`table message version ${version}; this page reads ${layout.format_version}: reload it`);
  }
  const length = view.getUint32(8, true);
  const header = JSON.parse(new TextDecoder().decode(bytes.slice(12, 12 + length)));
  const start = 12 + length;
  const arrays = {};
  for (const [name, entry] of Object.entries(header.arrays)) {
    const count = entry.shape.reduce((a, b) => a * b, 1);
    arrays[name] = {shape: entry.shape, data: new Uint16Array(buffer, start + entry.offset, count)};
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
