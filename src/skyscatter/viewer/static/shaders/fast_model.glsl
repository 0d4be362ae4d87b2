// The fast model: S. Hillaire, "A Scalable and Production Ready Sky and Atmosphere Rendering
// Technique", Computer Graphics Forum 39(4), EGSR 2020, doi:10.1111/cgf.14050. Three small
// LUTs made on the GPU from the atmosphere's description (viewer/gpu_fast.py), with no
// precomputed table: the transmittance to the top (256 x 64, Bruneton's mapping of
// parameterisation.glsl), the multiple scattering Psi_ms (32 x 32 over mu_s and altitude: the
// second order with an isotropic phase function, times the sum of the geometric series of
// the higher orders, 1 / (1 - f_ms); stored as log Psi_ms on the nodes of the CPU solver's
// table, transport/hillaire.py), and the sky seen from the camera's altitude (192 x 108
// over the view's azimuth from the sun and its zenith angle). Spectral: each LUT is a texture
// array with one layer per group of four wavelengths (one RGBA texel), all per unit
// irradiance of the star; the final pass converts to CIE XYZ with u_to_xyz (C_wc E_w).
// Uses sky.glsl's u_bottom_radius, u_top_radius, enter_atmosphere and sun_visible_fraction.

uniform highp sampler2DArray u_fast_transmittance;  // RGBA16F, one layer per group
uniform highp sampler2DArray u_fast_multiple;       // RGBA16F, log Psi_ms per unit irradiance
uniform highp sampler2DArray u_fast_sky_view;       // RGBA16F, radiance per unit irradiance
uniform highp sampler2DArray u_fast_irradiance;     // RGBA16F, the sky's on the ground
uniform highp sampler2D u_fast_density;  // R32F, density / its largest, level i of constituent
                                         // c at (i % PHASE_ROW, c * rows + i / PHASE_ROW)
uniform highp sampler2D u_fast_phase;    // RGBA32F (PHASE_ROW, n_c * n_g) [sr^-1]: texelFetch
uniform int u_fast_constituents;
uniform int u_fast_altitudes;
uniform int u_fast_density_rows;
uniform float u_fast_altitude_step;      // [m]
uniform int u_fast_groups;
uniform int u_fast_group;                // the group a LUT pass computes
// the coefficients at density 1 [m^-1] of constituent c in group g at g * MAX + c
uniform vec4 u_fast_extinction[FAST_MAX_CONSTITUENTS * FAST_MAX_GROUPS];
uniform vec4 u_fast_scattering[FAST_MAX_CONSTITUENTS * FAST_MAX_GROUPS];
uniform vec4 u_fast_albedo[FAST_MAX_GROUPS];  // the ground albedo of each group
uniform mat4x3 u_fast_to_xyz[FAST_MAX_GROUPS];  // XYZ of each group: C_wc E_w (columns w)
uniform float u_fast_view_radius;        // sky-view pass: the camera's r [m] ...
uniform float u_fast_view_mu_s;          // ... and the sun's cosine there
uniform float u_fast_mu_s_centre;        // the multiple-scattering LUT's c (fast_multiple_x)

// density of constituent c at altitude h [m], linear between the uniform levels, 0 above
float fast_density(int c, float h) {
    float f = h / u_fast_altitude_step;
    if (f >= float(u_fast_altitudes - 1)) return 0.0;
    f = max(f, 0.0);
    int i = int(f);
    int row = c * u_fast_density_rows;
    float low = texelFetch(u_fast_density, ivec2(i % PHASE_ROW, row + i / PHASE_ROW), 0).r;
    float high = texelFetch(u_fast_density,
                            ivec2((i + 1) % PHASE_ROW, row + (i + 1) / PHASE_ROW), 0).r;
    return mix(low, high, f - float(i));
}

// extinction coefficient [m^-1] of group g at radius r
vec4 fast_extinction(float r, int g) {
    vec4 extinction = vec4(0.0);
    float h = r - u_bottom_radius;
    for (int c = 0; c < FAST_MAX_CONSTITUENTS; ++c) {
        if (c >= u_fast_constituents) break;
        extinction += fast_density(c, h) * u_fast_extinction[g * FAST_MAX_CONSTITUENTS + c];
    }
    return extinction;
}

// phase function of constituent c for group g at cos(scattering angle) nu, linear in the
// angle between the PHASE_ROW samples (as sky.glsl's phase_value)
vec4 fast_phase(int c, float nu, int g) {
    float f = acos(clamp(nu, -1.0, 1.0)) / PI * float(PHASE_ROW - 1);
    int i = min(int(f), PHASE_ROW - 2);
    int row = c * u_fast_groups + g;
    vec4 low = texelFetch(u_fast_phase, ivec2(i, row), 0);
    vec4 high = texelFetch(u_fast_phase, ivec2(i + 1, row), 0);
    return mix(low, high, f - float(i));
}

// transmittance from radius r towards mu up to the top, of group g (the LUT)
vec4 fast_transmittance_to_top(float r, float mu, int g) {
    vec2 x = transmittance_x_from_r_mu(r, mu, u_bottom_radius, u_top_radius);
    vec2 uv = vec2(texture_coord_from_unit_range(x.x, FAST_TRANSMITTANCE_SIZE.x),
                   texture_coord_from_unit_range(x.y, FAST_TRANSMITTANCE_SIZE.y));
    return texture(u_fast_transmittance, vec3(uv, float(g)));
}

// the star's light reaching radius r with the sun at cosine mu_s: the transmittance to the top
// times the part of the disk above the horizon (sky.glsl's sun_visible_fraction); below the
// horizontal the sun's own ray down to the geometric horizon, whose ray serves below it (as
// transport/_kernels.py sun_columns: air above the ground sees the sun set later, through
// more air)
vec4 fast_sunlight(float r, float mu_s, int g) {
    float visible = sun_visible_fraction(r, mu_s);
    if (visible <= 0.0) return vec4(0.0);
    float mu_h = -horizon_distance(r, u_bottom_radius) / r;
    return visible * fast_transmittance_to_top(r, max(mu_s, mu_h), g);
}

// (x_mu, x_h) in [0, 1] of radius r and sun cosine mu_s in the multiple-scattering LUT, whose
// nodes are at x = k / (n - 1), texel centres (twin of transport/_hillaire_kernels.py
// multiple_scattering_coordinates): x_h = sqrt(h / H), rows crowded at the ground;
// x_mu = x_c +- (1 - x_c or x_c) sqrt(|mu_s - c| / (1 - c or 1 + c)), x_c = (1 + c) / 2,
// columns crowded at c = u_fast_mu_s_centre, where the sun sets for the air above
vec2 fast_multiple_x(float r, float mu_s) {
    float h = clamp((r - u_bottom_radius) / (u_top_radius - u_bottom_radius), 0.0, 1.0);
    float mu = clamp(mu_s, -1.0, 1.0);
    float c = u_fast_mu_s_centre;
    float x_c = 0.5 * (1.0 + c);
    float x_mu = mu >= c ? x_c + (1.0 - x_c) * sqrt((mu - c) / (1.0 - c))
                         : x_c - x_c * sqrt((c - mu) / (1.0 + c));
    return vec2(x_mu, sqrt(h));
}

// (r, mu_s) of the multiple-scattering LUT at x = (x_mu, x_h), the inverse of fast_multiple_x
// (twin of transport/hillaire.py multiple_scattering_nodes): h = H x_h^2 and
// mu_s = c +- (1 -+ c) ((x_mu - x_c) / (1 - x_c or x_c))^2 on either side of x_c
vec2 fast_multiple_r_mu_s(vec2 x) {
    float c = u_fast_mu_s_centre;
    float x_c = 0.5 * (1.0 + c);
    float above = (x.x - x_c) / (1.0 - x_c);
    float below = (x_c - x.x) / x_c;
    float mu_s = x.x >= x_c ? c + (1.0 - c) * above * above : c - (1.0 + c) * below * below;
    return vec2(mix(u_bottom_radius, u_top_radius, x.y * x.y), mu_s);
}

// Psi_ms of group g at radius r and sun cosine mu_s: exp of the LUT's log Psi_ms, bilinear
// between its nodes (fast_multiple_x) as the CPU solver's (Psi_ms falls by orders of
// magnitude between columns as the sun sets, where linear interpolation follows the brighter
// node; FAST_ZERO_LOG where Psi_ms = 0 gives 0 again)
vec4 fast_multiple_scattering(float r, float mu_s, int g) {
    vec2 x = fast_multiple_x(r, mu_s);
    vec2 uv = vec2(texture_coord_from_unit_range(x.x, FAST_MULTIPLE_SIZE.x),
                   texture_coord_from_unit_range(x.y, FAST_MULTIPLE_SIZE.y));
    return exp(texture(u_fast_multiple, vec3(uv, float(g))));
}

// The sky's irradiance on the ground per unit irradiance of the star, of group g at sun cosine
// mu_s (the LUT: x = (mu_s + 1) / 2)
vec4 fast_ground_irradiance(float mu_s, int g) {
    float u = texture_coord_from_unit_range(clamp(0.5 * (mu_s + 1.0), 0.0, 1.0),
                                            FAST_IRRADIANCE_SIZE.x);
    return texture(u_fast_irradiance, vec3(u, 0.5, float(g)));
}

// The radiance per unit irradiance of group g along the ray from (r, mu) (the ray's plane
// holds the sun: mu_s at the start, nu = cos(view, sun)) up to the ground or the top, with
// `steps` samples placed quadratically (dense near the camera, where a ground camera's air is
// densest): the sun's single scattering with each constituent's phase function (or the
// isotropic 1 / 4 pi where `isotropic`), the multiple scattering sigma_s Psi_ms unless
// `isotropic` (Hillaire's in-scattering), each segment integrated as exp(-sigma_e t) with its
// source held constant. The ground, where the ray meets it: Lambertian, lit by the sun and,
// unless `isotropic`, by the sky (the irradiance LUT, fast_irradiance.frag: our addition to
// Hillaire's LUTs, which light the ground by the sun alone). Also the transmittance along the ray (`through`)
// and, for the multiple-scattering pass, the integral of sigma_s T (`f_ms`).
vec4 fast_march(float r, float mu, float mu_s, float nu, int g, int steps, bool isotropic,
                out vec4 through, out vec4 f_ms) {
    bool ground = ray_intersects_ground(r, mu, u_bottom_radius);
    float d = ground ? distance_to_bottom_boundary(r, mu, u_bottom_radius)
                     : distance_to_top_boundary(r, mu, u_top_radius);
    vec4 phase[FAST_MAX_CONSTITUENTS];
    for (int c = 0; c < FAST_MAX_CONSTITUENTS; ++c) {
        if (c >= u_fast_constituents) break;
        phase[c] = isotropic ? vec4(0.25 / PI) : fast_phase(c, nu, g);
    }
    vec4 radiance = vec4(0.0);
    through = vec4(1.0);
    f_ms = vec4(0.0);
    float t_low = 0.0;
    for (int i = 0; i < steps; ++i) {
        float s = (float(i) + 1.0) / float(steps);
        float t_high = d * s * s;
        float dt = t_high - t_low;
        float t = 0.5 * (t_low + t_high);
        t_low = t_high;
        float r_t = sqrt(max(t * t + 2.0 * r * mu * t + r * r, 0.0));
        float mu_s_t = clamp((r * mu_s + t * nu) / r_t, -1.0, 1.0);
        vec4 extinction = vec4(0.0);
        vec4 source = vec4(0.0);
        vec4 sunlight = fast_sunlight(r_t, mu_s_t, g);
        vec4 scattering = vec4(0.0);
        float h = r_t - u_bottom_radius;
        for (int c = 0; c < FAST_MAX_CONSTITUENTS; ++c) {
            if (c >= u_fast_constituents) break;
            float n = fast_density(c, h);
            int k = g * FAST_MAX_CONSTITUENTS + c;
            extinction += n * u_fast_extinction[k];
            scattering += n * u_fast_scattering[k];
            source += n * u_fast_scattering[k] * phase[c] * sunlight;
        }
        if (!isotropic) source += scattering * fast_multiple_scattering(r_t, mu_s_t, g);
        vec4 segment = exp(-extinction * dt);
        vec4 share = mix(vec4(dt), (1.0 - segment) / max(extinction, vec4(1e-30)),
                         greaterThan(extinction, vec4(0.0)));
        radiance += through * source * share;
        f_ms += through * scattering * share;
        through *= segment;
    }
    if (ground) {
        float mu_s_g = clamp((r * mu_s + d * nu) / u_bottom_radius, -1.0, 1.0);
        vec4 light = fast_sunlight(u_bottom_radius, mu_s_g, g) * max(mu_s_g, 0.0);
        if (!isotropic) light += fast_ground_irradiance(mu_s_g, g);
        radiance += through * u_fast_albedo[g] / PI * light;
    }
    return radiance;
}

// The sky-view LUT's axes (Hillaire's "sky-view LUT", our own mapping): x = sqrt(phi / pi),
// phi the view's azimuth from the sun's (more texels towards the sun); the view's zenith angle
// in two halves as the scattering tables' mu axis (parameterisation.glsl scattering_u_mu):
// above the horizon v = 1/2 + 1/2 c(1 - sqrt(1 - theta / theta_h)), below it v = 1/2 - 1/2
// c(1 - sqrt(1 - (pi - theta) / (pi - theta_h))), c the texel-centre mapping of one half, so
// that the sky and the ground never mix and texels crowd at the horizon.
vec2 fast_sky_view_uv(float r, float mu, float cos_phi, bool hits_ground) {
    float x = sqrt(acos(clamp(cos_phi, -1.0, 1.0)) / PI);
    float u = texture_coord_from_unit_range(x, FAST_SKY_VIEW_SIZE.x);
    return vec2(u, scattering_u_mu(r, mu, hits_ground, u_bottom_radius, u_top_radius,
                                   FAST_SKY_VIEW_SIZE.y));
}

// The radiance [XYZ] towards `dir` from `origin` (world) with the sun towards `sun_dir`: from
// the sky-view LUT inside the atmosphere; with FAST_SPACE (a camera above the atmosphere,
// viewer.js "fast_space") by a march per pixel, as Hillaire's (a program of its own: the
// march's code in the LUT's program would cost it registers, as the clouds' did)
vec3 fast_sky_radiance(vec3 origin, vec3 dir, vec3 sun_dir) {
    vec4 entry = enter_atmosphere(origin, dir);
    if (entry.w == 0.0) return vec3(0.0);
    vec3 x = entry.xyz;
    float r = length(x);
    vec3 up = x / r;
    float mu = dot(up, dir);
    float mu_s = dot(up, sun_dir);
    float nu = dot(dir, sun_dir);
    vec3 radiance = vec3(0.0);
#ifdef FAST_SPACE
    r = min(r, u_top_radius);
    for (int g = 0; g < FAST_MAX_GROUPS; ++g) {
        if (g >= u_fast_groups) break;
        vec4 through, f_ms;
        radiance += u_fast_to_xyz[g] * fast_march(r, mu, mu_s, nu, g, FAST_SKY_VIEW_STEPS,
                                                  false, through, f_ms);
    }
    return radiance;
#endif
    r = clamp(r, u_bottom_radius, u_top_radius);
    float spread = sqrt(max((1.0 - mu * mu) * (1.0 - mu_s * mu_s), 0.0));
    float cos_phi = spread > SPREAD_MIN ? (nu - mu * mu_s) / spread : 1.0;
    vec2 uv = fast_sky_view_uv(r, mu, cos_phi, ray_intersects_ground(r, mu, u_bottom_radius));
    for (int g = 0; g < FAST_MAX_GROUPS; ++g) {
        if (g >= u_fast_groups) break;
        radiance += u_fast_to_xyz[g] * texture(u_fast_sky_view, vec3(uv, float(g)));
    }
    return radiance;
}

// The star's transmittance from `origin` towards `sun_dir` in XYZ, weighted by the star's
// spectrum as the tables' (gpu_tables): sum_w C_wc E_w T_w / sum_w C_wc E_w
vec3 fast_sun_transmittance(vec3 origin, vec3 sun_dir) {
    vec4 entry = enter_atmosphere(origin, sun_dir);
    float r = length(origin);
    if (r > u_top_radius) {
        if (entry.w == 0.0) return vec3(1.0);
        origin = entry.xyz;
        r = length(origin);
    }
    r = clamp(r, u_bottom_radius, u_top_radius);
    float mu = dot(origin, sun_dir) / r;
    if (ray_intersects_ground(r, mu, u_bottom_radius)) return vec3(0.0);
    vec3 light = vec3(0.0);
    for (int g = 0; g < FAST_MAX_GROUPS; ++g) {
        if (g >= u_fast_groups) break;
        light += u_fast_to_xyz[g] * fast_transmittance_to_top(r, mu, g);
    }
    return light / max(u_sun_irradiance, vec3(1e-30));
}
