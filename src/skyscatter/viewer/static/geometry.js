// Camera and frame geometry of the page (JavaScript twins of render/camera.py and
// render/scene.py, for the uniforms and for placing the sun under the pointer).

const DEG = Math.PI / 180;
export const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];

// twin of render.camera._basis: (right, up, forward) in ENU from heading, pitch, roll [rad]
export function cameraBasis(heading, pitch, roll) {
  const [sh, ch, sp, cp] = [Math.sin(heading), Math.cos(heading), Math.sin(pitch), Math.cos(pitch)];
  const forward = [sh * cp, ch * cp, sp];
  const up0 = [-sh * sp, -ch * sp, cp];
  const right0 = [ch, -sh, 0];
  const [sr, cr] = [Math.sin(roll), Math.cos(roll)];
  const up = up0.map((v, i) => cr * v + sr * right0[i]);
  const right = right0.map((v, i) => cr * v - sr * up0[i]);
  return [right, up, forward];
}

// twin of render.scene.orbit_viewpoint: columns east, north, up at (lat, lon) [rad]
export function localFrame(lat, lon) {
  const up = [Math.cos(lat) * Math.cos(lon), Math.cos(lat) * Math.sin(lon), Math.sin(lat)];
  const east = [-Math.sin(lon), Math.cos(lon), 0];
  return [east, cross(up, east), up];
}

// twin of render.scene.sun_direction: ENU unit vector from zenith and azimuth [deg]
export function sunDirection(zenithDeg, azimuthDeg) {
  const [z, a] = [zenithDeg * DEG, azimuthDeg * DEG];
  return [Math.sin(z) * Math.sin(a), Math.sin(z) * Math.cos(a), Math.cos(z)];
}

export function toWorld(frame, v) {
  return [0, 1, 2].map((i) => frame[0][i] * v[0] + frame[1][i] * v[1] + frame[2][i] * v[2]);
}

// Local ENU direction of canvas pixel (x, y) (twin of the cameras' `directions`, see camera.glsl)
export function pixelDirection(state, canvas, x, y) {
  const [w, h] = [canvas.clientWidth, canvas.clientHeight];
  if (state.projection === "perspective") {
    const tanV = Math.tan(state.fov * DEG / 2);
    const px = (2 * x / w - 1) * tanV * w / h;
    const py = (1 - 2 * y / h) * tanV;
    const [right, up, forward] = cameraBasis(state.heading * DEG, state.pitch * DEG, state.roll * DEG);
    const ray = [0, 1, 2].map((i) => forward[i] + px * right[i] + py * up[i]);
    const norm = Math.hypot(...ray);
    return ray.map((v) => v / norm);
  }
  const radius = Math.min(w, h) / 2;
  const [u, v] = [(x - w / 2) / radius, (y - h / 2) / radius];
  const rho = Math.hypot(u, v);
  const theta = state.fisheye_fov * DEG / 2 * rho;
  const s = rho > 0 ? Math.sin(theta) / rho : state.fisheye_fov * DEG / 2;
  return [-u * s, -v * s, Math.cos(theta)];
}


// twin of transport.air_shadows.shaded_stretch for one unit world ray from `origin` [m]: where
// it is below the sphere topR, before the sphere bottomR, at most maxM long: [start, end] [m]
export function shadedStretch(origin, ray, bottomR, topR, maxM) {
  const b = dot(ray, origin);
  const c = dot(origin, origin);
  const disc = b * b - c + topR * topR;
  const start = Math.max(-b - Math.sqrt(Math.max(disc, 0)), 0);
  const groundDisc = b * b - c + bottomR * bottomR;
  const ground = groundDisc > 0 && b < 0 ? -b - Math.sqrt(groundDisc) : Infinity;
  const end = Math.min(disc > 0 ? -b + Math.sqrt(disc) : 0, Math.max(ground, 0), start + maxM);
  return [start, Math.max(end, start)];
}

// twin of transport.air_shadows.map_frame: where the clouds' shadow map lies for world `rays`
// (unit) and their `stretches` ([start, end] [m]), the sun along unit `sun`, levels from
// radius lowR to highR [m]; `map` the layout's clouds.shadow_map. {e1, e2, corner [m],
// texel [m], shape [n_u, n_w], levels [first radius, spacing] [m]} or null (too coarse)
export function mapFrame(rays, stretches, sun, lowR, highR, map) {
  let e1 = cross(sun, Math.abs(sun[2]) < 0.9 ? [0, 0, 1] : [1, 0, 0]);
  e1 = e1.map((v) => v / Math.hypot(...e1));
  const e2 = cross(sun, e1);
  const low = [Infinity, Infinity];
  const high = [-Infinity, -Infinity];
  rays.forEach((ray, i) => {
    for (const t of stretches[i]) {
      const point = ray.map((v) => v * t);
      [dot(point, e1), dot(point, e2)].forEach((x, k) => {
        low[k] = Math.min(low[k], x);
        high[k] = Math.max(high[k], x);
      });
    }
  });
  const texel = Math.max(Math.max(high[0] - low[0], high[1] - low[1]) / (map.texels - 2), map.min_texel_m);
  if (texel > map.max_texel_m) return null;
  return {e1, e2, corner: low.map((v) => v - texel), texel,
          shape: [0, 1].map((k) => Math.ceil((high[k] - low[k]) / texel) + 2),
          levels: [lowR, (highR - lowR) / (map.levels - 1)]};
}

// twin of transport.adaptive_pixels.coarse_spacing for the page's w x h image (its rays every
// 8th row as there, and every 8th column): the largest power of two up to maxSpacing whose
// lattice points lie within `angle` [rad] of each other, from the median angle between
// horizontally neighbouring pixels
export function coarseSpacing(state, width, height, maxSpacing, angle) {
  const size = {clientWidth: width, clientHeight: height};
  const radius = Math.min(width, height) / 2;
  const hasRay = (x, y) => state.projection !== "fisheye" || Math.hypot(x - width / 2, y - height / 2) <= radius;
  const angles = [];
  for (let row = 0; row < height; row += 8) {
    for (let col = 0; col + 1 < width; col += 8) {
      const [x, y] = [col + 0.5, row + 0.5];
      if (!hasRay(x, y) || !hasRay(x + 1, y)) continue;
      const cosine = dot(pixelDirection(state, size, x, y), pixelDirection(state, size, x + 1, y));
      angles.push(Math.acos(Math.min(Math.max(cosine, -1), 1)));
    }
  }
  if (!angles.length) return 1;
  angles.sort((a, b) => a - b);
  const middle = angles.length >> 1;
  const step = angles.length % 2 ? angles[middle] : 0.5 * (angles[middle - 1] + angles[middle]);
  let spacing = 1;
  while (spacing < maxSpacing && 2 * spacing * step <= angle) spacing *= 2;
  return spacing;
}
