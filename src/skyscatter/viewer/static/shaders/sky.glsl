// Sky radiance from the tables: the GLSL twin of the lookups in
// transport/_table_lookup_kernels.py and transport/_table_common_kernels.py
// (sky_radiance_rays by day: the tables alone, as Bruneton 2017's GetSkyRadiance; the CPU
// renderer's twilight ray march of single scattering, below sun elevation 5 deg, is not done
// here). CIE XYZ, Y = luminance [cd m^-2]; tables decoded from viewer/gpu_tables.py's message.

uniform sampler2D u_transmittance;   // (n_r_t, n_mu_t) XYZ, linear filtering
uniform sampler2D u_irradiance;      // (n_r_e, n_mu_s_e) XYZ, linear filtering
uniform highp sampler3D u_scattering; // x = nu * n_mu_s + mu_s, y = mu, z = t * n_r + r
uniform sampler2D u_phase;           // texelFetch only
uniform vec2 u_transmittance_size;   // (n_mu_t, n_r_t)
uniform vec2 u_irradiance_size;      // (n_mu_s_e, n_r_e)
uniform vec4 u_scattering_shape;     // (n_r, n_mu, n_mu_s, n_nu)
uniform int u_n_tables;              // n_s single-scattering tables, n_c peak corrections
                                     // (clipped forward peaks) + 1 (orders >= 2)
uniform float u_phase_angles;        // samples of each phase function over [0, pi]
uniform int u_phase_rows;            // texture rows per phase-weighted table
uniform float u_transmittance_scale;
uniform float u_irradiance_scale;
uniform float u_phase_scale;
uniform float u_scattering_scales[MAX_TABLES];
uniform float u_bottom_radius;       // [m]
uniform float u_top_radius;          // [m]
uniform float u_mu_s_min;
uniform float u_sun_angle_share;  // of the mu_s axis (AtmosphereTables.sun_angle_share)
uniform vec3 u_ground_albedo;        // solar-weighted XYZ albedo
uniform vec3 u_sun_irradiance;       // XYZ of the star's irradiance at the top
uniform float u_sun_angular_radius;  // [rad]

// twin of transmittance_to_top
vec3 transmittance_to_top(float r, float mu) {
    vec2 x = transmittance_x_from_r_mu(r, mu, u_bottom_radius, u_top_radius);
    vec2 uv = vec2(texture_coord_from_unit_range(x.x, u_transmittance_size.x),
                   texture_coord_from_unit_range(x.y, u_transmittance_size.y));
    return texture(u_transmittance, uv).rgb * u_transmittance_scale;
}

// twin of transmittance_along
vec3 transmittance_along(float r, float mu, float d, bool hits_ground) {
    float r_d = sqrt(max(d * d + 2.0 * r * mu * d + r * r, 0.0));
    r_d = clamp(r_d, u_bottom_radius, u_top_radius);
    float mu_d = clamp((r * mu + d) / r_d, -1.0, 1.0);
    vec3 near_end, far_end;
    if (hits_ground) {
        near_end = transmittance_to_top(r_d, -mu_d);
        far_end = transmittance_to_top(r, -mu);
    } else {
        near_end = transmittance_to_top(r, mu);
        far_end = transmittance_to_top(r_d, mu_d);
    }
    return mix(vec3(0.0), min(near_end / max(far_end, vec3(1e-30)), vec3(1.0)),
               greaterThan(far_end, vec3(0.0)));
}

// twin of phase_values: phase function of constituent s, linear in the scattering angle
vec3 phase_value(int s, float nu) {
    float f = acos(clamp(nu, -1.0, 1.0)) / PI * (u_phase_angles - 1.0);
    f = clamp(f, 0.0, u_phase_angles - 1.0);
    int i = min(int(f), int(u_phase_angles) - 2);
    float a = f - float(i);
    int row = s * u_phase_rows;
    vec3 low = texelFetch(u_phase, ivec2(i % PHASE_ROW, row + i / PHASE_ROW), 0).rgb;
    vec3 high = texelFetch(u_phase, ivec2((i + 1) % PHASE_ROW, row + (i + 1) / PHASE_ROW), 0).rgb;
    return mix(low, high, a) * u_phase_scale;
}

// One table t of the scattering texture at (u_r, u_mu, u_mu_s) and the nu slices i_nu, i_nu + 1
// (twin of scattering_lookup: trilinear in hardware, linear in nu by hand)
vec3 scattering_table(int t, float u_r, float u_mu, float u_mu_s, int i_nu, float a_nu) {
    float n_nu = u_scattering_shape.w;
    float z = (float(t) + u_r) / float(u_n_tables);
    vec3 low = texture(u_scattering, vec3((float(i_nu) + u_mu_s) / n_nu, u_mu, z)).rgb;
    vec3 high = texture(u_scattering, vec3((float(i_nu + 1) + u_mu_s) / n_nu, u_mu, z)).rgb;
    return mix(low, high, a_nu) * u_scattering_scales[t];
}

// twin of irradiance_lookup
vec3 irradiance_lookup(float r, float mu_s) {
    vec2 x = irradiance_x_from_r_mu_s(r, mu_s, u_bottom_radius, u_top_radius);
    vec2 uv = vec2(texture_coord_from_unit_range(x.x, u_irradiance_size.x),
                   texture_coord_from_unit_range(x.y, u_irradiance_size.y));
    return texture(u_irradiance, uv).rgb * u_irradiance_scale;
}

// twin of transport.geometry.sun_visible_fraction
float sun_visible_fraction(float r, float mu_s) {
    float mu_h = -horizon_distance(r, u_bottom_radius) / r;
    float sin_h = sqrt(1.0 - mu_h * mu_h);
    if (mu_s >= mu_h * cos(u_sun_angular_radius) + sin_h * sin(u_sun_angular_radius)) {
        return 1.0;
    }
    float elevation = acos(mu_h) - acos(clamp(mu_s, -1.0, 1.0));
    float x = elevation / u_sun_angular_radius;
    if (x >= 1.0) return 1.0;
    if (x <= -1.0) return 0.0;
    return 0.5 + (x * sqrt(1.0 - x * x) + asin(x)) / PI;
}

// twin of _enter_atmosphere: an observer in space moves to the top boundary along the ray;
// w = 0 when the ray misses the atmosphere
vec4 enter_atmosphere(vec3 origin, vec3 dir) {
    float r = length(origin);
    if (r <= u_top_radius) return vec4(origin, 1.0);
    float r_mu = dot(origin, dir);
    float discriminant = r_mu * r_mu - (r - u_top_radius) * (r + u_top_radius);
    if (r_mu >= 0.0 || discriminant < 0.0) return vec4(origin, 0.0);
    float d = -r_mu - sqrt(discriminant);
    return vec4(origin + d * dir, 1.0);
}

// the scattering tables' coordinates (u_r, u_mu, u_mu_s) at (r, mu, mu_s) in the half of the
// mu axis `hits_ground` names, and the nu node i_nu below nu with the weight a_nu of the next
void scattering_coordinates(float r, float mu, float mu_s, float nu, bool hits_ground,
                            out vec3 u, out int i_nu, out float a_nu) {
    u.x = scattering_u_r(r, u_bottom_radius, u_top_radius, u_scattering_shape.x);
    u.y = scattering_u_mu(r, mu, hits_ground, u_bottom_radius, u_top_radius,
                          u_scattering_shape.y);
    u.z = scattering_u_mu_s(mu_s, u_bottom_radius, u_top_radius, u_mu_s_min,
                            u_sun_angle_share, u_scattering_shape.z);
    float f_nu = clamp(scattering_u_nu(nu, mu, mu_s) * (u_scattering_shape.w - 1.0), 0.0,
                       u_scattering_shape.w - 1.0);
    i_nu = min(int(f_nu), int(u_scattering_shape.w) - 2);
    a_nu = f_nu - float(i_nu);
}

// Single scattering of each constituent with its phase function, the peak corrections with
// their clipped phase functions, plus the orders >= 2, at (r, mu, mu_s, nu) in the half of the mu axis `hits_ground` names (twin of
// scattering_corners + scattering_lookup with the phase weights)
vec3 sky_scattering(float r, float mu, float mu_s, float nu, bool hits_ground) {
    vec3 u;
    int i_nu;
    float a_nu;
    scattering_coordinates(r, mu, mu_s, nu, hits_ground, u, i_nu, a_nu);
    vec3 radiance = vec3(0.0);
    for (int t = 0; t < MAX_TABLES; ++t) {
        if (t >= u_n_tables) break;
        vec3 weight = t < u_n_tables - 1 ? phase_value(t, nu) : vec3(1.0);
        radiance += weight * scattering_table(t, u.x, u.y, u.z, i_nu, a_nu);
    }
    return radiance;
}

// twin of sky_radiance_rays (day branch): sum_s p_s(nu) S_s + sum_c p*_c(nu) D_c + M, plus for
// rays that hit the ground the Lambertian ground lit by the sun and the sky, seen through the
// air; the part `ground_sunlit` of the sunlight reaches the ground (the clouds' shadow:
// surfaces.py)
vec3 sky_radiance(vec3 origin, vec3 dir, vec3 sun_dir, float ground_sunlit) {
    vec4 entry = enter_atmosphere(origin, dir);
    if (entry.w == 0.0) return vec3(0.0);
    vec3 x = entry.xyz;
    float r = length(x);
    float mu = dot(x, dir) / r;
    float mu_s = dot(x, sun_dir) / r;
    float nu = dot(dir, sun_dir);
    r = clamp(r, u_bottom_radius, u_top_radius);
    bool hits_ground = ray_intersects_ground(r, mu, u_bottom_radius);
    vec3 radiance = sky_scattering(r, mu, mu_s, nu, hits_ground);
    if (hits_ground) {
        float d = distance_to_bottom_boundary(r, mu, u_bottom_radius);
        float mu_s_g = clamp((r * mu_s + d * nu) / u_bottom_radius, -1.0, 1.0);
        vec3 t_view = transmittance_along(r, mu, d, true);
        float direct = max(mu_s_g, 0.0) * sun_visible_fraction(u_bottom_radius, mu_s_g);
        vec3 t_sun = transmittance_to_top(u_bottom_radius, max(mu_s_g, 0.0));
        vec3 ground = u_sun_irradiance * t_sun * direct * ground_sunlit
                      + irradiance_lookup(u_bottom_radius, mu_s_g);
        radiance += u_ground_albedo / PI * ground * t_view;
    }
    return radiance;
}

// The air between the observer at `origin` and `point` (twin of _aerial_point by day): the
// light it scatters towards the observer, S(x, v) - T(x, p) S(p, v) with both lookups in the
// half of the mu axis of the ray at x (Bruneton 2017, GetSkyRadianceToPoint), into
// `inscattered`; returns the segment's transmittance T(x, p)
vec3 aerial_perspective(vec3 origin, vec3 point, vec3 sun_dir, out vec3 inscattered) {
    inscattered = vec3(0.0);
    vec3 dir = point - origin;
    float d = length(dir);
    if (!(d > 0.0)) return vec3(1.0);
    dir /= d;
    vec4 entry = enter_atmosphere(origin, dir);
    if (entry.w == 0.0) return vec3(1.0);
    vec3 x = entry.xyz;
    d -= length(x - origin);
    if (d <= 0.0) return vec3(1.0);
    float r = length(x);
    float mu = dot(x, dir) / r;
    float mu_s = dot(x, sun_dir) / r;
    float nu = dot(dir, sun_dir);
    r = clamp(r, u_bottom_radius, u_top_radius);
    bool hits_ground = ray_intersects_ground(r, mu, u_bottom_radius);
    d = min(d, hits_ground ? distance_to_bottom_boundary(r, mu, u_bottom_radius)
                           : distance_to_top_boundary(r, mu, u_top_radius));
    float r_p = sqrt(max(d * d + 2.0 * r * mu * d + r * r, 0.0));
    float mu_p = clamp((r * mu + d) / r_p, -1.0, 1.0);
    float mu_s_p = clamp((r * mu_s + d * nu) / r_p, -1.0, 1.0);
    r_p = clamp(r_p, u_bottom_radius, u_top_radius);
    vec3 transmittance = transmittance_along(r, mu, d, hits_ground);
    inscattered = max(sky_scattering(r, mu, mu_s, nu, hits_ground)
                      - transmittance * sky_scattering(r_p, mu_p, mu_s_p, nu, hits_ground),
                      vec3(0.0));
    return transmittance;
}

// The star's transmittance from `origin` towards `sun_dir` (twin of LutSolver.transmittance
// to infinity): 0 when the planet is in the way
vec3 sun_transmittance(vec3 origin, vec3 sun_dir) {
    vec4 entry = enter_atmosphere(origin, sun_dir);
    float r = length(origin);
    if (r > u_top_radius) {
        if (entry.w == 0.0) return vec3(1.0);  // above the air, nothing in the way
        origin = entry.xyz;
        r = length(origin);
    }
    r = clamp(r, u_bottom_radius, u_top_radius);
    float mu = dot(origin, sun_dir) / r;
    if (ray_intersects_ground(r, mu, u_bottom_radius)) return vec3(0.0);
    return transmittance_to_top(r, mu);
}
