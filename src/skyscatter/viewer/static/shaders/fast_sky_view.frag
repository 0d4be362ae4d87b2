// The fast model's sky-view LUT (fast_model.glsl; Hillaire 2020's "sky-view LUT"): the
// radiance per unit irradiance seen from radius u_fast_view_radius with the sun at cosine
// u_fast_view_mu_s, at the view azimuth and zenith angle of texel (i, j), the inverse of
// fast_sky_view_uv, marched with FAST_SKY_VIEW_STEPS samples.

out vec4 frag_colour;

void main() {
    float r = u_fast_view_radius;
    float mu_s = u_fast_view_mu_s;
    float x = (gl_FragCoord.x - 0.5) / (FAST_SKY_VIEW_SIZE.x - 1.0);
    float phi = PI * x * x;
    float half_n = floor(FAST_SKY_VIEW_SIZE.y / 2.0);
    int j = int(gl_FragCoord.y);
    bool ground = float(j) < half_n;
    float k = ground ? half_n - 1.0 - float(j) : float(j) - half_n;
    float a = 1.0 - (1.0 - k / (half_n - 1.0)) * (1.0 - k / (half_n - 1.0));
    float theta_h = horizon_zenith_angle(r, u_bottom_radius);
    float theta = ground ? PI - a * (PI - theta_h) : a * theta_h;
    float mu = cos(theta);
    float nu = sin(theta) * sqrt(max(1.0 - mu_s * mu_s, 0.0)) * cos(phi) + mu * mu_s;
    vec4 through, f_ms;
    frag_colour = fast_march(r, mu, mu_s, nu, u_fast_group, FAST_SKY_VIEW_STEPS, false, through,
                             f_ms);
}
