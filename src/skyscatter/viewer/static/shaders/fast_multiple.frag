// The fast model's multiple-scattering LUT (fast_model.glsl; Hillaire 2020's "multiple
// scattering LUT"): at texel (i, j) the sun's cosine mu_s = 2 i / (w - 1) - 1 and the radius
// r = R_b + j / (h - 1) (R_t - R_b). Over FAST_MULTIPLE_DIRECTIONS directions spread evenly
// over the sphere (a spherical Fibonacci set), each marched to the ground or the top: L_2 the
// mean of the sun's single scattering with the isotropic phase function (and the ground it
// lights), f_ms the mean of the integral of sigma_s T (the light a unit isotropic source
// sends back); Psi_ms = L_2 / (1 - f_ms), the geometric series of the orders >= 2.

out vec4 frag_colour;

void main() {
    vec2 x = (gl_FragCoord.xy - 0.5) / (FAST_MULTIPLE_SIZE - 1.0);
    float mu_s = 2.0 * x.x - 1.0;
    float r = mix(u_bottom_radius, u_top_radius, x.y);
    vec3 sun = vec3(sqrt(max(1.0 - mu_s * mu_s, 0.0)), 0.0, mu_s);
    vec4 second = vec4(0.0);
    vec4 f_ms = vec4(0.0);
    const float GOLDEN_ANGLE = 2.39996322972865332;
    for (int k = 0; k < FAST_MULTIPLE_DIRECTIONS; ++k) {
        float mu = 1.0 - (2.0 * float(k) + 1.0) / float(FAST_MULTIPLE_DIRECTIONS);
        float s = sqrt(max(1.0 - mu * mu, 0.0));
        float phi = GOLDEN_ANGLE * float(k);
        vec3 dir = vec3(s * cos(phi), s * sin(phi), mu);
        vec4 through, transfer;
        second += fast_march(r, mu, mu_s, dot(dir, sun), u_fast_group, FAST_MULTIPLE_STEPS, true,
                             through, transfer);
        f_ms += transfer;
    }
    second /= float(FAST_MULTIPLE_DIRECTIONS);
    f_ms /= float(FAST_MULTIPLE_DIRECTIONS);
    frag_colour = second / max(1.0 - f_ms, vec4(1e-3));
}
