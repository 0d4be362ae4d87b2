// Clouds: the GLSL twin of atmosphere/_cloud_sampling.py (the water content w(p)) and
// transport/_cloud_kernels.py (march_clouds and its helpers, same names), the compositing
// of transport/clouds.py (clouds_in_front) and transport/_air_shadow_kernels.py (the clouds'
// shadows in the air), in CIE XYZ (viewer/gpu_clouds.py: the optics per
// channel, weighted by the star's spectrum). The arrays come from viewer/gpu_clouds.py's
// message; the constants (columns of the parameter table, the march's steps) from
// generated/constants.glsl.
//
// Positions are relative to the camera (d = p - camera, world axes), so that float32 keeps
// centimetres: the noise coordinates are q(d) = q_camera + A d with A the tile scale times the
// stretch along the wind, and q_camera = A (camera - wind offset) reduced modulo the tile in
// double precision by the page (viewer.js `cloudOrigins`), three per layer: the shape, the
// slowly varying coverage ("weather", axes permuted) and the detail tile. The radius of a
// point is |camera + d| (0.5 m in float32 at the Earth's radius).
//
// Departures from the CPU renderer: the far field of layers beyond FAR_START (the
// independent column approximation) and coverage maps are not drawn (a ground view does not
// reach FAR_START: 1300 km for the cumulus preset); the light tables over (radius, sun
// zenith cosine) are the atmosphere's tables read directly (cloud_light), not resampled on
// transport.clouds.cloud_lighting's grid; the clouds' shadows in the air (air_shadow_loss)
// take the air's single scattering from table differences, where transport.air_shadows
// integrates the air's densities; both read the clouds' water from a shadow map of the same
// frame (the page's fitted to a grid of its rays, cloud_map.frag drawing it in float32 and
// storing float16).

uniform vec3 u_camera_position;             // planet-centred [m]
uniform vec3 u_sun_direction;               // world, unit
uniform int u_cloud_layers;                 // 0: no clouds
uniform int u_n_single;                     // n_s single-scattering tables (sky.glsl's first)
uniform highp sampler3D u_cloud_noise;      // RG: shape, detail (gpu_clouds: layers stacked)
// each layer's first 4 CLOUD_PARAM_VEC4S columns of the parameter table (viewer.js
// cloudUniforms): uniforms, not a texture, as each sample of the water reads a dozen
uniform vec4 u_cloud_params[MAX_CLOUD_LAYERS * CLOUD_PARAM_VEC4S];
uniform highp sampler2D u_cloud_profiles;   // RG32F (n_rows, n_layers), texelFetch
uniform highp sampler2D u_cloud_phase;      // RGB32F (CLOUD_PHASE_ANGLES, n_layers), XYZ
uniform highp sampler2D u_cloud_optics;     // RGB32F (3, n_layers): k_ext [m^2 g^-1], albedo, g
uniform float u_cloud_texture_size;         // n, texels per tile side
uniform vec3 u_cloud_ground_shade;          // transport.clouds.ground_shade, XYZ
uniform vec3 u_cloud_origin[3 * MAX_CLOUD_LAYERS];  // q_camera: shape, weather, detail [texels]
// The shadow map (cloud_map.frag; transport.air_shadows.MapFrame): three RGBA16F textures of
// four levels each (low, middle, high), the layers stacked along their height, n_w rows each;
// lines through camera + u e1 + w e2 with u, w = corner + (i + 0.5, j + 0.5) texel; levels at
// radii x + k y; none drawn (u_map_on 0): no shadows in the air
uniform highp sampler2D u_cloud_map_low;
uniform highp sampler2D u_cloud_map_middle;
uniform highp sampler2D u_cloud_map_high;
uniform int u_map_on;
uniform vec3 u_map_e1;
uniform vec3 u_map_e2;
uniform vec2 u_map_corner;      // [m]
uniform float u_map_texel;      // [m]
uniform vec2 u_map_size;        // n_u, n_w
uniform vec2 u_map_levels;      // first radius, spacing [m]
// The adaptive refinement over the pixels (viewer.js drawRefinedClouds), RGBA32F of the image's
// size: the radiance behind the clouds (cloud_behind.frag), and each pixel's T (XYZ) and hit,
// and A (XYZ) of L = T L_behind + A, known so far (cloud_level.frag, cloud_scatter.frag)
uniform highp sampler2D u_behind;
uniform highp sampler2D u_known_t;
uniform highp sampler2D u_known_a;

float cloud_param(int layer, int column) {
    return u_cloud_params[layer * CLOUD_PARAM_VEC4S + column / 4][column % 4];
}

vec3 cloud_optics(int layer, int which) {
    return texelFetch(u_cloud_optics, ivec2(which, layer), 0).rgb;
}

// twin of _cloud_sampling.sample_texture: trilinear, periodic, texel centres at i + 0.5; q in
// texels (x, y, z of the tile). The depth axis holds the layers, each n + 1 slices deep (the
// last repeats the first), so that x wraps by hand and the hardware never mixes two layers
float sample_texture(int layer, int channel, vec3 q) {
    float n = u_cloud_texture_size;
    float x = mod(q.x, n);
    if (x < 0.5) x += n;
    float depth = float(textureSize(u_cloud_noise, 0).z);
    vec2 value = texture(u_cloud_noise, vec3(q.z / n, q.y / n,
                                             (float(layer) * (n + 1.0) + x) / depth)).rg;
    return channel == 0 ? value.r : value.g;
}

// twin of _cloud_sampling._profile
float cloud_profile(int layer, int n_nodes, float h) {
    for (int k = 1; k < MAX_PROFILE_NODES; ++k) {
        if (k >= n_nodes) break;
        vec2 node = texelFetch(u_cloud_profiles, ivec2(k, layer), 0).rg;
        if (h <= node.x) {
            vec2 previous = texelFetch(u_cloud_profiles, ivec2(k - 1, layer), 0).rg;
            float t = (h - previous.x) / (node.x - previous.x);
            return previous.y * (1.0 - t) + node.y * t;
        }
    }
    return texelFetch(u_cloud_profiles, ivec2(n_nodes - 1, layer), 0).g;
}

// twin of _cloud_sampling._water: water content [g m^-3] of `layer` at d from the camera,
// with the detail noise's erosion when `detail`
// twin of _cloud_sampling.edge_margin: where d lies on the layer's edge ramp, in ramps (> 0
// inside the smooth cloud; -1e9 outside the shell or where the coverage is 0); m: the point
// moved by the wind and stretched, for the detail noise
float cloud_ramp(int layer, vec3 d, out vec3 m) {
    m = d;
    float r = length(u_camera_position + d);
    float base = cloud_param(layer, CLOUD_BASE_R);
    float top = cloud_param(layer, CLOUD_TOP_R);
    if (r < base || r > top) return -1e9;
    float h = cloud_param(layer, CLOUD_SHEET) > 0.0 ? 0.5 : (r - base) / (top - base);
    // moved by the wind (in q_camera), stretched along it
    vec3 along = vec3(cloud_param(layer, CLOUD_ALONG_X), cloud_param(layer, CLOUD_ALONG_Y),
                      cloud_param(layer, CLOUD_ALONG_Z));
    float stretch = cloud_param(layer, CLOUD_STRETCH_MINUS_ONE);
    m = d - dot(d, along) * (stretch / (1.0 + stretch)) * along;
    float tile = cloud_param(layer, CLOUD_INV_SCALE) * u_cloud_texture_size;
    float coverage = cloud_param(layer, CLOUD_COVERAGE)
                     * cloud_profile(layer, int(cloud_param(layer, CLOUD_N_PROFILE)), h);
    float variation = cloud_param(layer, CLOUD_VARIATION);
    if (variation > 0.0) {
        float large = tile / COVERAGE_TILE_RATIO;
        // a different slice of the same tile: axes permuted, so no common period
        float weather = sample_texture(layer, 0, u_cloud_origin[3 * layer + 1] + m.zxy * large);
        coverage *= 1.0 + variation * (2.0 * weather - 1.0);
    }
    if (coverage <= 0.0) return -1e9;
    coverage = min(coverage, 1.0);
    float shape = sample_texture(layer, 0, u_cloud_origin[3 * layer] + m * tile);
    return (shape - (1.0 - coverage)) / (cloud_param(layer, CLOUD_EDGE) * coverage);
}

float cloud_water(int layer, vec3 d, bool detail) {
    vec3 m;
    float density = cloud_ramp(layer, d, m);
    if (density <= 0.0) return 0.0;
    density = min(density, 1.0);
    float strength = cloud_param(layer, CLOUD_DETAIL);
    if (detail && strength > 0.0) {
        float fine = cloud_param(layer, CLOUD_INV_DETAIL_SCALE) * u_cloud_texture_size;
        float erosion = strength * sample_texture(layer, 1, u_cloud_origin[3 * layer + 2]
                                                            + m * fine);
        density = (density - erosion) / (1.0 - erosion);
        if (density <= 0.0) return 0.0;
    }
    return cloud_param(layer, CLOUD_WATER) * density;
}

// twin of _cloud_kernels._sphere_roots: roots of |o + t v|^2 = radius^2, b = o . v, r_o = |o|,
// with c - radius^2 as (r_o - radius)(r_o + radius); vec2(-1e30) for none
vec2 sphere_roots(float b, float r_o, float radius) {
    float disc = b * b - (r_o - radius) * (r_o + radius);
    if (disc < 0.0) return vec2(-1e30);
    float root = sqrt(disc);
    return vec2(-b - root, -b + root);
}

// twin of _cloud_kernels._exit_length: from d inside a layer's shell along `dir` to its edge
float exit_length(vec3 d, float r, vec3 dir, float base_r, float top_r) {
    float b = dot(u_camera_position + d, dir);
    float t_top = sphere_roots(b, r, top_r).y;
    vec2 s = sphere_roots(b, r, base_r);
    if (s.x > -1e29 && s.x > 0.0) return min(t_top, s.x);
    return t_top;
}

// twin of _cloud_kernels._path_water: water path [g m^-2] from d along `dir` over `len` [m],
// midpoint sums on segments from `first` [m], doubling; the water without its erosion
float path_water(int layer, vec3 d, vec3 dir, float len, float first) {
    float total = 0.0;
    float start = 0.0;
    float segment = first;
    for (int i = 0; i < 32; ++i) {
        if (start >= len) break;
        float end = min(start + segment, len);
        total += cloud_water(layer, d + 0.5 * (start + end) * dir, false) * (end - start);
        start = end;
        segment *= 2.0;
    }
    return total;
}

// The light tables of transport.clouds.cloud_lighting, read from the atmosphere's tables at
// (r, mu_s): the air's transmittance towards the sun (0 below the horizon), the clear sky's
// diffuse irradiance from above, and the irradiance the ground reflects up, risen to r
void cloud_light(float r, float mu_s, out vec3 sun_air, out vec3 sky_down, out vec3 ground_up) {
    r = clamp(r, u_bottom_radius, u_top_radius);
    sun_air = ray_intersects_ground(r, mu_s, u_bottom_radius) ? vec3(0.0)
                                                             : transmittance_to_top(r, mu_s);
    sky_down = irradiance_lookup(r, mu_s);
    float direct = mu_s > 0.0 ? mu_s * sun_visible_fraction(u_bottom_radius, mu_s) : 0.0;
    vec3 reflected = u_ground_albedo
                     * (u_sun_irradiance * transmittance_to_top(u_bottom_radius, max(mu_s, 0.0))
                        * direct + irradiance_lookup(u_bottom_radius, mu_s));
    ground_up = reflected * transmittance_along(u_bottom_radius, 1.0, r - u_bottom_radius, false);
}

// twin of _two_stream.beam_passed (per channel)
vec3 beam_passed(vec3 gamma_depth, vec3 through, float mu0) {
    return (1.0 + through + 1.5 * mu0 * (1.0 - through)) / (2.0 * (1.0 + gamma_depth));
}

// twin of _two_stream.beam_source (per channel: g and gamma are vec3)
vec3 beam_source(vec3 g, vec3 gamma, vec3 lit, vec3 far, vec3 direct, vec3 through, float mu0,
                 float forward) {
    vec3 net = beam_passed(gamma * (lit + far), through, mu0);
    vec3 total = 1.0 - net - 2.0 * gamma * net * lit + 1.5 * mu0 * (1.0 - direct);
    return total / (2.0 * PI) + 3.0 * g * forward * (net - direct) / (4.0 * PI);
}

// twin of _two_stream.diffuse_source
vec3 diffuse_source(vec3 g, vec3 gamma, vec3 lit, vec3 far, float forward) {
    vec3 net = 1.0 / (1.0 + gamma * (lit + far));
    vec3 total = (1.0 + 2.0 * gamma * far) * net;
    return total / (2.0 * PI) + 3.0 * g * forward * net / (4.0 * PI);
}

// twin of _cloud_kernels._light_source: J at radius r from the water paths towards the sun,
// away from it, above and below [g m^-2]
vec3 light_source(int layer, float r, float mu_s, float mu_view, float w_sun, float w_anti,
                  float w_up, float w_down, vec3 sun_phase) {
    vec3 sun_air, down, up;
    cloud_light(r, mu_s, sun_air, down, up);
    vec3 k_ext = cloud_optics(layer, 0);
    vec3 g = cloud_optics(layer, 2);
    vec3 gamma = EDDINGTON * (1.0 - g);
    float slab_mu = max(mu_s, 0.0);
    vec3 sun = u_sun_irradiance * sun_air;  // E_sun T_air
    vec3 direct = exp(-k_ext * w_sun);
    vec3 diffuse_sun = sun * slab_mu * beam_source(
        g, gamma, k_ext * w_sun * slab_mu, k_ext * w_anti * slab_mu, direct,
        direct * exp(-k_ext * w_anti), slab_mu, mu_view);
    vec3 d_up = k_ext * w_up;
    vec3 d_down = k_ext * w_down;
    vec3 sky = down * diffuse_source(g, gamma, d_up, d_down, mu_view)
               + up * u_cloud_ground_shade * diffuse_source(g, gamma, d_down, d_up, -mu_view);
    return sun * sun_phase * direct + max(diffuse_sun, vec3(0.0)) + max(sky, vec3(0.0));
}

// twin of _cloud_kernels._source_at: J at t along the view ray v inside a volume layer
vec3 source_at(int layer, vec3 v, float t, vec3 sun_dir, vec3 sun_phase) {
    vec3 d = t * v;
    vec3 p = u_camera_position + d;
    float radius = length(p);
    vec3 up = p / radius;
    float base_r = cloud_param(layer, CLOUD_BASE_R);
    float top_r = cloud_param(layer, CLOUD_TOP_R);
    float r = clamp(radius, base_r, top_r);
    float len = min(exit_length(d, r, sun_dir, base_r, top_r), LIGHT_MAX_M);
    float w_sun = path_water(layer, d, sun_dir, len, LIGHT_FIRST_M);
    len = min(exit_length(d, r, -sun_dir, base_r, top_r), LIGHT_MAX_M);
    float w_anti = path_water(layer, d, -sun_dir, len, AMBIENT_FIRST_M);
    float w_up = path_water(layer, d, up, top_r - r, AMBIENT_FIRST_M);
    float w_down = path_water(layer, d, -up, r - base_r, AMBIENT_FIRST_M);
    return light_source(layer, r, dot(up, sun_dir), dot(up, v), w_sun, w_anti, w_up, w_down,
                        sun_phase);
}

// twin of _cloud_kernels._segment_integral (one channel)
float segment_integral(float j0, float j1, float sigma, float step, float e) {
    if (j0 > 0.0 && j1 > 0.0) {
        float a = log(j0 / j1) / step;
        float rate = sigma + a;
        if (abs(rate * step) < 1e-6) return j0 * sigma * step;
        return j0 * sigma * (1.0 - exp(-rate * step)) / rate;
    }
    if (sigma * step < 1e-8) return 0.5 * (j0 + j1) * sigma * step;
    float slope = (j1 - j0) / step;
    return j0 * (1.0 - e) + slope * (1.0 - e * (1.0 + sigma * step)) / sigma;
}

// twin of _cloud_kernels._mean_depth
float mean_depth(float sigma, float step, float e) {
    if (sigma * step < 1e-4) return 0.5 * step;
    return 1.0 / sigma - step * e / (1.0 - e);
}

// twin of _cloud_kernels._fine_step
float fine_step(float t) {
    return max(STEP_M, STEP_GROWTH * t);
}

// twin of cloud_noise.hash32 (lowbias32, Wellons 2018) and _cloud_kernels._jitter
float jitter(uint index) {
    uint x = index;
    x ^= x >> 16u;
    x *= 0x7FEB352Du;
    x ^= x >> 15u;
    x *= 0x846CA68Bu;
    x ^= x >> 16u;
    return (float(x) + 0.5) / 4294967296.0;
}

// twin of _cloud_kernels._cloud_edge
float cloud_edge(int layer, vec3 v, float outside, float inside) {
    if (cloud_water(layer, outside * v, true) > 0.0) return outside;
    for (int i = 0; i < EDGE_BISECTIONS; ++i) {
        float middle = 0.5 * (outside + inside);
        if (cloud_water(layer, middle * v, true) > 0.0) inside = middle;
        else outside = middle;
    }
    return inside;
}

// twin of _cloud_kernels._phases_at for one layer: XYZ phase [sr^-1] at cos(angle) nu
vec3 cloud_phase(int layer, float nu) {
    float theta = acos(clamp(nu, -1.0, 1.0));
    float x = sqrt(theta / PI) * float(CLOUD_PHASE_ANGLES - 1);
    int i = min(int(x), CLOUD_PHASE_ANGLES - 2);
    float w = x - float(i);
    return texelFetch(u_cloud_phase, ivec2(i, layer), 0).rgb * (1.0 - w)
           + texelFetch(u_cloud_phase, ivec2(i + 1, layer), 0).rgb * w;
}

// Adds one channel's segment: glow += T albedo int J sigma e^(-sigma x), T *= e^(-sigma step)
void add_segment(inout vec3 trans, inout vec3 glow, vec3 albedo, vec3 start, vec3 end,
                 vec3 sigma, float step) {
    vec3 e = exp(-sigma * step);
    glow += trans * albedo * vec3(segment_integral(start.x, end.x, sigma.x, step, e.x),
                                  segment_integral(start.y, end.y, sigma.y, step, e.y),
                                  segment_integral(start.z, end.z, sigma.z, step, e.z));
    trans *= e;
}

// twin of _cloud_kernels._march_layer: one crossing [t0, t1] of a volume layer; `state` =
// (transmittance-weighted distance, its weight, hit, stop). The Y channel plays the CPU's
// middle wavelength (step lengths, depth weights)
void march_layer(int layer, vec3 v, float t0, float t1, float jitter_, vec3 sun_dir,
                 vec3 sun_phase, inout vec3 trans, inout vec3 glow, inout vec4 state) {
    vec3 extinction = cloud_optics(layer, 0);
    vec3 albedo = cloud_optics(layer, 1);
    vec3 start_source = vec3(0.0);
    float s = t0;
    float last_empty = t0;
    bool coarse = true;
    bool inside = false;
    bool have_start = false;
    int empties = 0;
    float thick_cap = 1e30;
    bool refined = false;
    for (int steps = 1; steps <= MAX_STEPS; ++steps) {
        if (!(s < t1)) break;
        float step = max(min(fine_step(s) * (coarse ? float(COARSE_STEPS) : 1.0), thick_cap),
                         (t1 - s) / float(MAX_STEPS + 1 - steps));
        step = min(step, t1 - s);
        float t = s + jitter_ * step;
        float water = cloud_water(layer, t * v, true);
        if (water <= 0.0) {
            vec3 m;
            refined = false;
            have_start = false;
            inside = false;
            last_empty = t;
            if (cloud_ramp(layer, t * v, m) > -NEAR_EDGE) {  // near an edge: short steps
                empties = 0;
                coarse = false;
                thick_cap = NEAR_STEP_M;
                // a long step is looked at again from its sample on, a short one is done
                s = step > NEAR_STEP_M ? t : s + step;
                continue;
            }
            empties += 1;
            coarse = coarse || empties >= EMPTY_TO_COARSE;
            thick_cap = 1e30;
            s += step;
            continue;
        }
        if (!inside) {  // entering a cloud: start the segments at its edge
            s = cloud_edge(layer, v, last_empty, t);
            inside = true;
            coarse = false;
            continue;
        }
        thick_cap = max(OPTICAL_STEP / (extinction.y * water), MIN_STEP_M);
        if (step > 1.5 * thick_cap && !refined) {  // too thick: walk it again, shorter
            refined = true;
            continue;
        }
        refined = false;
        empties = 0;
        state.z = 1.0;
        if (!have_start) start_source = source_at(layer, v, s, sun_dir, sun_phase);
        vec3 end_source = source_at(layer, v, s + step, sun_dir, sun_phase);
        float sigma_mid = extinction.y * water;
        float extinct_mid = exp(-sigma_mid * step);
        float weight = trans.y * (1.0 - extinct_mid);
        state.x += weight * (s + mean_depth(sigma_mid, step, extinct_mid));
        state.y += weight;
        add_segment(trans, glow, albedo, start_source, end_source, extinction * water, step);
        if (all(lessThanEqual(trans, vec3(TRANSMITTANCE_CUTOFF)))) {
            state.w = 1.0;
            return;
        }
        start_source = end_source;
        have_start = true;
        s += step;
    }
}

// twin of _cloud_kernels._cross_sheet: one sample in the middle of the chord [t0, t1]
void cross_sheet(int layer, vec3 v, float t0, float t1, vec3 sun_dir, vec3 sun_phase,
                 inout vec3 trans, inout vec3 glow, inout vec4 state) {
    float t = 0.5 * (t0 + t1);
    vec3 d = t * v;
    float water = cloud_water(layer, d, true);
    if (water <= 0.0) return;
    state.z = 1.0;
    vec3 p = u_camera_position + d;
    float r = length(p);
    float mu_s = dot(p, sun_dir) / r;
    float half_ = 0.5 * (cloud_param(layer, CLOUD_TOP_R) - cloud_param(layer, CLOUD_BASE_R));
    float slant = water * min(half_ / max(abs(mu_s), 0.05), LIGHT_MAX_M);
    vec3 source = light_source(layer, r, mu_s, dot(p, v) / r, slant, slant, water * half_,
                               water * half_, sun_phase);
    float len = t1 - t0;
    vec3 extinction = cloud_optics(layer, 0);
    float lost = 1.0 - exp(-extinction.y * water * len);
    state.x += trans.y * lost * t;
    state.y += trans.y * lost;
    vec3 e = exp(-extinction * water * len);
    glow += trans * cloud_optics(layer, 1) * source * (1.0 - e);
    trans *= e;
}

// The (at most two) intervals of t in [0, t_max] where the ray from the camera lies between
// the spheres base_r and top_r (twin of _cloud_kernels._shell_intervals); returns their number
int shell_intervals(vec3 v, float base_r, float top_r, float t_max, out vec4 pieces) {
    float r_o = length(u_camera_position);
    float b = dot(u_camera_position, v);
    pieces = vec4(0.0);
    vec2 t = sphere_roots(b, r_o, top_r);
    if (t.x < -1e29) return 0;
    vec2 s = sphere_roots(b, r_o, base_r);
    if (s.x < -1e29) s = vec2(t.y);  // the ray's line misses the inner sphere
    int count = 0;
    float lo = max(t.x, 0.0), hi = min(min(t.y, s.x), t_max);
    if (hi > lo) { pieces.xy = vec2(lo, hi); count = 1; }
    lo = max(max(t.x, s.y), 0.0);
    hi = min(t.y, t_max);
    if (hi > lo) {
        if (count == 0) pieces.xy = vec2(lo, hi);
        else pieces.zw = vec2(lo, hi);
        count += 1;
    }
    return count;
}

// twin of _cloud_kernels._ground_distance from the camera
float ground_distance(vec3 v) {
    float b = dot(u_camera_position, v);
    if (b >= 0.0) return 1e30;
    vec2 t = sphere_roots(b, length(u_camera_position), u_bottom_radius);
    return t.x < -1e29 ? 1e30 : max(t.x, 0.0);
}

// twin of _cloud_kernels.march_clouds for one ray v from the camera up to t_max [m]: the
// clouds' radiance (XYZ) into `glow`, their transmittance into `trans`; returns (depth, hit):
// the transmittance-weighted distance of their scattering and whether any cloud was met
vec2 march_clouds(vec3 v, float t_max, vec3 sun_dir, uint index, out vec3 trans,
                  out vec3 glow) {
    trans = vec3(1.0);
    glow = vec3(0.0);
    vec4 state = vec4(0.0);
    float starts[2 * MAX_CLOUD_LAYERS];
    float ends[2 * MAX_CLOUD_LAYERS];
    int layers[2 * MAX_CLOUD_LAYERS];
    int count = 0;
    t_max = min(t_max, ground_distance(v));
    for (int layer = 0; layer < MAX_CLOUD_LAYERS; ++layer) {
        if (layer >= u_cloud_layers) break;
        vec4 pieces;
        int found = shell_intervals(v, cloud_param(layer, CLOUD_BASE_R),
                                    cloud_param(layer, CLOUD_TOP_R), t_max, pieces);
        for (int k = 0; k < 2; ++k) {
            if (k >= found) break;
            float lo = k == 0 ? pieces.x : pieces.z;
            float hi = k == 0 ? pieces.y : pieces.w;
            int at = count;  // insertion sort by the start
            while (at > 0 && starts[at - 1] > lo) {
                starts[at] = starts[at - 1];
                ends[at] = ends[at - 1];
                layers[at] = layers[at - 1];
                at -= 1;
            }
            starts[at] = lo;
            ends[at] = hi;
            layers[at] = layer;
            count += 1;
        }
    }
    float nu = dot(v, sun_dir);
    float jitter_ = jitter(index);
    for (int o = 0; o < 2 * MAX_CLOUD_LAYERS; ++o) {
        if (o >= count) break;
        int layer = layers[o];
        vec3 sun_phase = cloud_phase(layer, nu);
        if (cloud_param(layer, CLOUD_SHEET) > 0.0) {
            cross_sheet(layer, v, starts[o], ends[o], sun_dir, sun_phase, trans, glow, state);
        } else {
            march_layer(layer, v, starts[o], ends[o], jitter_, sun_dir, sun_phase, trans, glow,
                        state);
        }
        if (state.w > 0.0) break;
    }
    return vec2(state.y > 0.0 ? state.x / state.y : 0.0, state.z);
}

// twin of _cloud_kernels.cloud_water_paths for one layer: its water path [g m^-2] from d
// (relative to the camera) along `dir` up to `max_distance` [m], the ground or beyond the
// layer, midpoint steps of STEP_M
float layer_water_path(int layer, vec3 d, vec3 dir, float max_distance) {
    vec3 o = u_camera_position + d;
    float r_o = length(o);
    float b = dot(o, dir);
    float t_max = max_distance;
    if (b < 0.0) {
        vec2 g = sphere_roots(b, r_o, u_bottom_radius);
        if (g.x > -1e29) t_max = min(t_max, max(g.x, 0.0));
    }
    vec2 t = sphere_roots(b, r_o, cloud_param(layer, CLOUD_TOP_R));
    if (t.x < -1e29) return 0.0;
    vec2 s = sphere_roots(b, r_o, cloud_param(layer, CLOUD_BASE_R));
    if (s.x < -1e29) s = vec2(t.y);
    bool sheet = cloud_param(layer, CLOUD_SHEET) > 0.0;
    float total = 0.0;
    for (int k = 0; k < 2; ++k) {
        float lo = k == 0 ? max(t.x, 0.0) : max(max(t.x, s.y), 0.0);
        float hi = k == 0 ? min(min(t.y, s.x), t_max) : min(t.y, t_max);
        if (!(hi > lo)) continue;
        int steps = sheet ? 1 : min(MAX_STEPS, max(1, int(ceil((hi - lo) / STEP_M))));
        float dt = (hi - lo) / float(steps);
        for (int i = 0; i < MAX_STEPS; ++i) {
            if (i >= steps) break;
            total += cloud_water(layer, d + (lo + (float(i) + 0.5) * dt) * dir, true) * dt;
        }
    }
    return total;
}

// twin of transport.clouds.cloud_transmittance (_cloud_kernels.cloud_water_paths): the
// clouds' transmittance from d (relative to the camera) along `dir` up to `max_distance` [m]
// or the ground, midpoint steps of STEP_M
vec3 cloud_transmittance(vec3 d, vec3 dir, float max_distance) {
    vec3 depth = vec3(0.0);
    for (int layer = 0; layer < MAX_CLOUD_LAYERS; ++layer) {
        if (layer >= u_cloud_layers) break;
        depth += cloud_optics(layer, 0) * layer_water_path(layer, d, dir, max_distance);
    }
    return exp(-depth);
}

float map_level(int k) {
    return u_map_levels.x + float(k) * u_map_levels.y;
}

// level k of the map at texture coordinates uv (bilinear: the hardware's, on float16)
float map_level_water(int k, vec2 uv) {
    int group = k / 4;
    vec4 texel = group == 0 ? texture(u_cloud_map_low, uv)
               : group == 1 ? texture(u_cloud_map_middle, uv) : texture(u_cloud_map_high, uv);
    return texel[k - 4 * group];
}

// twin of _air_shadow_kernels._sun_water for one layer: its water [g m^-2] towards the sun
// from d (relative to the camera) at radius r, bilinear across the map, linear in radius
// between its levels; 0 at or above the highest level
float map_water(int layer, vec3 d, float r) {
    if (r >= map_level(MAP_LEVELS - 1)) return 0.0;
    vec2 ij = clamp((vec2(dot(d, u_map_e1), dot(d, u_map_e2)) - u_map_corner) / u_map_texel,
                    vec2(0.5), u_map_size - 0.5);
    vec2 uv = vec2(ij.x / u_map_size.x,
                   (float(layer) * u_map_size.y + ij.y) / (float(u_cloud_layers) * u_map_size.y));
    float f = clamp((r - u_map_levels.x) / u_map_levels.y, 0.0, float(MAP_LEVELS - 1));
    int k = min(int(f), MAP_LEVELS - 2);
    f -= float(k);
    return map_level_water(k, uv) * (1.0 - f) + map_level_water(k + 1, uv) * f;
}

// The phase-weighted and the plain sums of the single-scattering tables (no orders >= 2) at
// (r, mu, mu_s, nu) in the half of the mu axis `hits_ground` names, seen from the observer
// through `through` (the air's transmittance to there): T sum_s p_s(nu) S_s and T sum_s S_s
void single_scattering_sums(float r, float mu, float mu_s, float nu, bool hits_ground,
                            vec3 through, out vec3 weighted, out vec3 plain) {
    vec3 u;
    int i_nu;
    float a_nu;
    scattering_coordinates(r, mu, mu_s, nu, hits_ground, u, i_nu, a_nu);
    weighted = vec3(0.0);
    plain = vec3(0.0);
    for (int t = 0; t < MAX_TABLES - 1; ++t) {
        if (t >= u_n_single) break;
        vec3 table = scattering_table(t, u.x, u.y, u.z, i_nu, a_nu);
        weighted += phase_value(t, nu) * table;
        plain += table;
    }
    weighted *= through;
    plain *= through;
}

// twin of _air_shadow_kernels.shadow_loss (transport.air_shadows): the light the air along
// the view ray v no longer scatters towards the observer because the clouds shade it, on the
// stretch below the highest cloud top, before `stop`, the ground and SHADOW_MAX_M:
// dL = sum_j [(1 - T_c) sum_s p_s(nu) dS_s - mu_s max(N - T_c, 0) / (2 pi) sum_s dS_s], with
// dS_s the single scattering of constituent s on sample j's stretch (the difference of two
// table lookups, as aerial_perspective; the CPU integrates the air's densities instead) and
// T_c, N the clouds' direct transmittance and two-stream net flux towards the sun from the
// sample, their water from the shadow map (map_water)
vec3 air_shadow_loss(vec3 v, vec3 sun_dir, float stop, uint index) {
    if (u_map_on == 0) return vec3(0.0);
    float top_r = 0.0;
    for (int layer = 0; layer < MAX_CLOUD_LAYERS; ++layer) {
        if (layer >= u_cloud_layers) break;
        top_r = max(top_r, cloud_param(layer, CLOUD_TOP_R));
    }
    float r_o = length(u_camera_position);
    float b = dot(u_camera_position, v);
    vec2 top = sphere_roots(b, r_o, top_r);
    if (top.x < -1e29 || r_o > u_top_radius) return vec3(0.0);
    float t_a = max(top.x, 0.0);
    float t_b = min(min(top.y, stop), min(ground_distance(v), t_a + SHADOW_MAX_M));
    if (!(t_b > t_a)) return vec3(0.0);
    float r = clamp(r_o, u_bottom_radius, u_top_radius);
    float mu = b / r_o;
    float mu_s = dot(u_camera_position, sun_dir) / r_o;
    float nu = dot(v, sun_dir);
    bool hits_ground = ray_intersects_ground(r, mu, u_bottom_radius);
    float jitter_ = jitter(index);
    float len = t_b - t_a;
    vec3 loss = vec3(0.0);
    vec3 weighted_lo, plain_lo;
    float d = t_a;
    single_scattering_sums(r, mu, mu_s, nu, hits_ground, vec3(1.0), weighted_lo, plain_lo);
    if (d > 0.0) {
        float r_d = sqrt(max(d * d + 2.0 * r * mu * d + r * r, 0.0));
        single_scattering_sums(clamp(r_d, u_bottom_radius, u_top_radius),
                               clamp((r * mu + d) / r_d, -1.0, 1.0),
                               clamp((r * mu_s + d * nu) / r_d, -1.0, 1.0), nu, hits_ground,
                               transmittance_along(r, mu, d, hits_ground), weighted_lo,
                               plain_lo);
    }
    for (int j = 0; j < SHADOW_SAMPLES; ++j) {
        float lo = t_a + len * pow(float(j) / float(SHADOW_SAMPLES), 2.0);
        float hi = t_a + len * pow(float(j + 1) / float(SHADOW_SAMPLES), 2.0);
        float r_d = sqrt(max(hi * hi + 2.0 * r * mu * hi + r * r, 0.0));
        vec3 weighted_hi, plain_hi;
        single_scattering_sums(clamp(r_d, u_bottom_radius, u_top_radius),
                               clamp((r * mu + hi) / r_d, -1.0, 1.0),
                               clamp((r * mu_s + hi * nu) / r_d, -1.0, 1.0), nu, hits_ground,
                               transmittance_along(r, mu, hi, hits_ground), weighted_hi,
                               plain_hi);
        vec3 weighted = max(weighted_lo - weighted_hi, vec3(0.0));
        vec3 plain = max(plain_lo - plain_hi, vec3(0.0));
        weighted_lo = weighted_hi;
        plain_lo = plain_hi;
        float t = lo + jitter_ * (hi - lo);
        vec3 p = u_camera_position + t * v;
        float r_p = length(p);
        float mu_s_p = dot(p, sun_dir) / r_p;
        vec3 tau = vec3(0.0);
        vec3 gamma_tau = vec3(0.0);
        for (int layer = 0; layer < MAX_CLOUD_LAYERS; ++layer) {
            if (layer >= u_cloud_layers) break;
            vec3 depth = cloud_optics(layer, 0) * map_water(layer, t * v, r_p);
            tau += depth;
            gamma_tau += EDDINGTON * (1.0 - cloud_optics(layer, 2)) * depth;
        }
        if (all(equal(tau, vec3(0.0)))) continue;
        vec3 direct = exp(-tau);
        vec3 slab = beam_passed(gamma_tau * max(mu_s_p, 0.0), direct, max(mu_s_p, 0.0));
        loss += weighted * (1.0 - direct)
                - plain * max(mu_s_p, 0.0) * max(slab - direct, vec3(0.0)) / (2.0 * PI);
    }
    return loss;
}

// twin of transport.clouds._CloudsOver.march for one ray v from the camera: the clouds in
// front of whatever lies behind them, with the air between and the light the clouds' shadows
// take from it (air_shadow_loss, dL), as L = T L_behind + A: T = T_c and
// A = -T_c S + max(S - dL, 0) + T_air L_c; a ray that meets no cloud (hit 0) T = 1, A = -dL
void clouds_over(vec3 v, vec3 sun_dir, float t_max, uint index, out vec3 t, out vec3 a,
                 out float hit) {
    vec3 glow;
    vec2 depth_hit = march_clouds(v, t_max, sun_dir, index, t, glow);
    hit = depth_hit.y;
    if (hit == 0.0) {
        t = vec3(1.0);
        a = -air_shadow_loss(v, sun_dir, t_max, index);
        return;
    }
    float depth = depth_hit.x;
    vec3 air_light;
    vec3 air_transmittance = aerial_perspective(u_camera_position,
                                                u_camera_position + depth * v, sun_dir,
                                                air_light);
    vec3 loss = air_shadow_loss(v, sun_dir, depth, index);
    a = max(air_light - loss, vec3(0.0)) - t * air_light + air_transmittance * glow;
}

// twin of transport.clouds.clouds_in_front for one ray: the clouds put in front of `behind`
// (the sky or ground without them), at least 0
vec3 clouds_in_front(vec3 v, vec3 sun_dir, vec3 behind, float t_max, uint index) {
    vec3 t, a;
    float hit;
    clouds_over(v, sun_dir, t_max, index, t, a, hit);
    return max(t * behind + a, vec3(0.0));
}

// twin of cloud_far_field.surface_cloud_transmittance with `diffuse` (its march, at the
// middle wavelength: here Y): the share of the sunlight on the horizontal that reaches d
// (relative to the camera) through the clouds, directly or scattered, the product of each
// layer's beam_passed
float cloud_sunlight(vec3 d, vec3 sun_dir) {
    float mu_s = max(dot(normalize(u_camera_position + d), sun_dir), 0.0);
    float passed = 1.0;
    for (int layer = 0; layer < MAX_CLOUD_LAYERS; ++layer) {
        if (layer >= u_cloud_layers) break;
        float depth = cloud_optics(layer, 0).y * layer_water_path(layer, d, sun_dir, 1e30);
        float gamma = EDDINGTON * (1.0 - cloud_optics(layer, 2).y);
        passed *= beam_passed(vec3(gamma * depth * mu_s), vec3(exp(-depth)), mu_s).y;
    }
    return passed;
}

// render/scene.py diffuse_radiance's background with clouds along world `dir`: the sky, or
// the ground with its sunlight passed by the clouds (render/surfaces.py)
vec3 radiance_behind_clouds(vec3 dir, vec3 sun_dir) {
    float t_ground = ground_distance(dir);
    float sunlit = t_ground < 1e29 ? cloud_sunlight(t_ground * dir, sun_dir) : 1.0;
    return sky_radiance(u_camera_position, dir, sun_dir, sunlit);
}
