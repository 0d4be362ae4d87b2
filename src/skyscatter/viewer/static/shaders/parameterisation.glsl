// Table parameterisations of the viewer: the GLSL twin of transport/table_parameterisation.py
// (same function names, same formulas; its module docstring documents them). Compared with the
// Python versions on a grid by tests/viewer/test_glsl_mapping.py in headless Chromium.
// r^2 - R^2 is written (r - R)(r + R) throughout: the same number, without the float32
// cancellation of two squares of ~4e13 m^2 (which made distances to the ground metres off).

// twin of texture_coord_from_unit_range
float texture_coord_from_unit_range(float x, float n) {
    return 0.5 / n + x * (1.0 - 1.0 / n);
}

// twin of distance_to_top_boundary
float distance_to_top_boundary(float r, float mu, float top_radius) {
    float discriminant = r * r * mu * mu - (r - top_radius) * (r + top_radius);
    return max(-r * mu + sqrt(max(discriminant, 0.0)), 0.0);
}

// twin of distance_to_bottom_boundary
float distance_to_bottom_boundary(float r, float mu, float bottom_radius) {
    float discriminant = r * r * mu * mu - (r - bottom_radius) * (r + bottom_radius);
    return max(-r * mu - sqrt(max(discriminant, 0.0)), 0.0);
}

// twin of ray_intersects_ground
bool ray_intersects_ground(float r, float mu, float bottom_radius) {
    return mu < 0.0 && r * r * mu * mu - (r - bottom_radius) * (r + bottom_radius) >= 0.0;
}

float horizon_distance(float r, float bottom_radius) {
    return sqrt(max((r - bottom_radius) * (r + bottom_radius), 0.0));
}

// twin of transmittance_x_from_r_mu: (x_mu, x_r)
vec2 transmittance_x_from_r_mu(float r, float mu, float bottom_radius, float top_radius) {
    float big_h = horizon_distance(top_radius, bottom_radius);
    float rho = horizon_distance(r, bottom_radius);
    float x_r = clamp(rho / big_h, 0.0, 1.0);
    float d_min = top_radius - r;
    float d_max = rho + big_h;
    if (d_max <= d_min) {
        return vec2(0.0, x_r);
    }
    float d = distance_to_top_boundary(r, mu, top_radius);
    return vec2(clamp((d - d_min) / (d_max - d_min), 0.0, 1.0), x_r);
}

// the scattering table's radius warp (AtmosphereTables.radius_warp): RADIUS_WARP_SEGMENTS + 1
// values, four per vec4
uniform vec4 u_radius_warp[RADIUS_WARP_VEC4S];
// 1 where the warp is the identity (Bruneton's axis): its reads are skipped, 4 % of a frame
uniform int u_radius_warp_identity;

float radius_warp_value(int k) {
    return u_radius_warp[k / 4][k % 4];
}

// twin of warped, on u_radius_warp
float warped_radius(float x) {
    float f = clamp(x, 0.0, 1.0) * float(RADIUS_WARP_SEGMENTS);
    int k = min(int(f), RADIUS_WARP_SEGMENTS - 1);
    float low = radius_warp_value(k);
    return low + (f - float(k)) * (radius_warp_value(k + 1) - low);
}

// twin of scattering_u_r, with the warp u_radius_warp
float scattering_u_r(float r, float bottom_radius, float top_radius, float n_r) {
    float big_h = horizon_distance(top_radius, bottom_radius);
    float rho = horizon_distance(r, bottom_radius);
    float x = min(rho / big_h, 1.0);
    return texture_coord_from_unit_range(u_radius_warp_identity == 1 ? x : warped_radius(x), n_r);
}

// twin of horizon_zenith_angle
float horizon_zenith_angle(float r, float bottom_radius) {
    return atan(bottom_radius, -horizon_distance(r, bottom_radius));
}

// twin of horizon_dense_from_angle
float horizon_dense_from_angle(float a) {
    return 1.0 - sqrt(max(1.0 - a, 0.0));
}

// twin of scattering_u_mu
float scattering_u_mu(float r, float mu, bool ray_hits_ground, float bottom_radius,
                      float top_radius, float n_mu) {
    float theta_h = horizon_zenith_angle(r, bottom_radius);
    float c = clamp(mu, -1.0, 1.0);
    float theta = atan(sqrt(max((1.0 - c) * (1.0 + c), 0.0)), c);
    float half_n = floor(n_mu / 2.0);
    if (ray_hits_ground) {
        float x = horizon_dense_from_angle((PI - theta) / (PI - theta_h));
        return 0.5 - 0.5 * texture_coord_from_unit_range(clamp(x, 0.0, 1.0), half_n);
    }
    float x = horizon_dense_from_angle(theta / theta_h);
    return 0.5 + 0.5 * texture_coord_from_unit_range(clamp(x, 0.0, 1.0), half_n);
}

// twin of scattering_u_mu_s (with mu_s_mapping_constants inlined)
float scattering_u_mu_s(float mu_s, float bottom_radius, float top_radius, float mu_s_min,
                        float sun_angle_share, float n_mu_s) {
    float d_min = top_radius - bottom_radius;
    float d_max = horizon_distance(top_radius, bottom_radius);
    float big_a = (distance_to_top_boundary(bottom_radius, mu_s_min, top_radius) - d_min)
                  / (d_max - d_min);
    float d = distance_to_top_boundary(bottom_radius, mu_s, top_radius);
    float a = (d - d_min) / (d_max - d_min);
    float x = max(1.0 - a / big_a, 0.0) / (1.0 + a);
    if (sun_angle_share > 0.0) {
        float x_theta = 1.0 - sqrt(max(1.0 - mu_s, 0.0) / (1.0 - mu_s_min));
        x = (1.0 - sun_angle_share) * x + sun_angle_share * max(x_theta, 0.0);
    }
    return texture_coord_from_unit_range(x, n_mu_s);
}

// twin of scattering_u_nu: 1 - phi / pi, phi the view's azimuth from the sun's
float scattering_u_nu(float nu, float mu, float mu_s) {
    float spread = sqrt(max((1.0 - mu * mu) * (1.0 - mu_s * mu_s), 0.0));
    float cos_phi = spread > SPREAD_MIN ? (nu - mu * mu_s) / spread : 1.0;
    return 1.0 - acos(clamp(cos_phi, -1.0, 1.0)) / PI;
}

// twin of irradiance_x_from_r_mu_s: (x_mu_s, x_r)
vec2 irradiance_x_from_r_mu_s(float r, float mu_s, float bottom_radius, float top_radius) {
    float x_r = (r - bottom_radius) / (top_radius - bottom_radius);
    return vec2(clamp(0.5 * (mu_s + 1.0), 0.0, 1.0), clamp(x_r, 0.0, 1.0));
}

// twin of transmittance_r_mu_from_x: (r, mu) of (x_mu, x_r)
vec2 transmittance_r_mu_from_x(float x_mu, float x_r, float bottom_radius, float top_radius) {
    float big_h = horizon_distance(top_radius, bottom_radius);
    float rho = big_h * x_r;
    float r = sqrt(rho * rho + bottom_radius * bottom_radius);
    float d_min = top_radius - r;
    float d_max = rho + big_h;
    float d = d_min + x_mu * (d_max - d_min);
    if (d <= 0.0) return vec2(r, 1.0);
    return vec2(r, clamp((big_h - rho) * (big_h + rho) / (2.0 * r * d) - d / (2.0 * r), -1.0, 1.0));
}
