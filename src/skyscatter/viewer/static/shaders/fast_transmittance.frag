// The fast model's transmittance LUT (fast_model.glsl): texel (i, j) holds exp(-tau) from
// (r, mu) = transmittance_r_mu_from_x(i / (w - 1), j / (h - 1)) to the top of the atmosphere,
// tau by the midpoint rule on FAST_TRANSMITTANCE_STEPS steps placed quadratically (dense at
// the ray's start: 40 equal steps left 1 % of the aerosol's optical depth out of rays that
// leave the ground at a low angle), for the four wavelengths of group u_fast_group.

out vec4 frag_colour;

void main() {
    vec2 x = (gl_FragCoord.xy - 0.5) / (FAST_TRANSMITTANCE_SIZE - 1.0);
    vec2 r_mu = transmittance_r_mu_from_x(x.x, x.y, u_bottom_radius, u_top_radius);
    float r = r_mu.x;
    float mu = r_mu.y;
    float d = distance_to_top_boundary(r, mu, u_top_radius);
    vec4 depth = vec4(0.0);
    float t_low = 0.0;
    for (int i = 0; i < FAST_TRANSMITTANCE_STEPS; ++i) {
        float s = (float(i) + 1.0) / float(FAST_TRANSMITTANCE_STEPS);
        float t_high = d * s * s;
        float t = 0.5 * (t_low + t_high);
        float r_t = sqrt(max(t * t + 2.0 * r * mu * t + r * r, 0.0));
        depth += fast_extinction(r_t, u_fast_group) * (t_high - t_low);
        t_low = t_high;
    }
    frag_colour = exp(-depth);
}
