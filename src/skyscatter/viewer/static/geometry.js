// Camera and frame geometry of the page (JavaScript twins of render/camera.py and
// render/scene.py, for the uniforms and for placing the sun under the pointer).

const DEG = Math.PI / 180;

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
  const north = [up[1] * east[2] - up[2] * east[1], up[2] * east[0] - up[0] * east[2],
                 up[0] * east[1] - up[1] * east[0]];
  return [east, north, up];
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

