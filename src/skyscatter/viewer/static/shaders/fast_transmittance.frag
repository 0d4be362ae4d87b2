// The fast model's transmittance LUT (fast_model.glsl): texel (i, j) holds exp(-tau) from
// (r, mu) = transmittance_r_mu_from_x(i / (w - 1), j / (h - 1)) to the top of the atmosphere,
// tau by the midpoint rule on FAST_TRANSMITTANCE_STEPS equal steps, for the four wavelengths
// of group u_fast_group.

out vec4 frag_colour;

void main() {
    vec2 x = (gl_FragCoord.xy - 0.5) / (FAST_TRANSMITTANCE_SIZE - 1.0);
    vec2 r_mu = transmittance_r_mu_from_x(x.x, x.y, u_bottom_radius, u_top_radius);
    float r = r_mu.x;
    float mu = r_mu.y;
    float dt = distance_to_top_boundary(r, mu, u_top_radius) / float(FAST_TRANSMITTANCE_STEPS);
    vec4 depth = vec4(0.0);
    for (int i = 0; i < FAST_TRANSMITTANCE_STEPS; ++i) {
        float t = (float(i) + 0.5) * dt;
        vec4 extinction, scattering;
        fast_medium(sqrt(max(t * t + 2.0 * r * mu * t + r * r, 0.0)), extinction, scattering);
        depth += extinction * dt;
    }
    frag_colour = exp(-depth);
}
