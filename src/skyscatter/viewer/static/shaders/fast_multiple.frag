// The fast model's multiple-scattering LUT (fast_model.glsl; Hillaire 2020's "multiple
// scattering LUT"), the CPU solver's table (transport/_hillaire_kernels.py
// multiple_scattering_table) on the GPU: at texel (i, j) the radius and sun's cosine of its
// node (i / (w - 1), j / (h - 1)) (fast_multiple_r_mu_s), and its directions: FAST_GAUSS_NODES
// Gauss-Legendre zenith cosines on each side of the node's horizon (the light jumps there,
// from the ground to the sky) x FAST_MULTIPLE_AZIMUTHS midpoint azimuths, each marched to the
// ground or the top (fast_march, FAST_MULTIPLE_STEPS samples): L_2 the integral of the sun's
// single scattering with the isotropic phase function (and the ground it lights) times
// 1 / 4 pi, f_ms that of the integral of sigma_s T (the light a unit isotropic source sends
// back); Psi_ms = L_2 / (1 - f_ms), the geometric series of the orders >= 2, stored as its
// log (FAST_ZERO_LOG where it is 0: the night side's full shadow).

out vec4 frag_colour;

void main() {
    vec2 x = (gl_FragCoord.xy - 0.5) / (FAST_MULTIPLE_SIZE - 1.0);
    vec2 node = fast_multiple_r_mu_s(x);
    float r = node.x;
    float mu_s = node.y;
    vec3 sun = vec3(sqrt(max(1.0 - mu_s * mu_s, 0.0)), 0.0, mu_s);
    vec4 second = vec4(0.0);
    vec4 f_ms = vec4(0.0);
    float mu_h = -horizon_distance(r, u_bottom_radius) / r;
    for (int k = 0; k < 2 * FAST_GAUSS_NODES; ++k) {
        bool sky = k < FAST_GAUSS_NODES;
        float low = sky ? mu_h : -1.0;
        float high = sky ? 1.0 : mu_h;
        int n = k % FAST_GAUSS_NODES;
        float mu = low + (high - low) * 0.5 * (FAST_GAUSS_X[n] + 1.0);
        float s = sqrt(max(1.0 - mu * mu, 0.0));
        // the solid angle over 4 pi: 1/2 (high - low) w_n x 2 pi / FAST_MULTIPLE_AZIMUTHS
        float weight = 0.25 * (high - low) * FAST_GAUSS_W[n] / float(FAST_MULTIPLE_AZIMUTHS);
        for (int m = 0; m < FAST_MULTIPLE_AZIMUTHS; ++m) {
            float phi = 2.0 * PI * (float(m) + 0.5) / float(FAST_MULTIPLE_AZIMUTHS);
            vec3 dir = vec3(s * cos(phi), s * sin(phi), mu);
            vec4 through, transfer;
            second += weight * fast_march(r, mu, mu_s, dot(dir, sun), u_fast_group,
                                          FAST_MULTIPLE_STEPS, true, through, transfer);
            f_ms += weight * transfer;
        }
    }
    vec4 psi = second / max(1.0 - f_ms, vec4(1e-3));
    frag_colour = mix(vec4(FAST_ZERO_LOG), log(max(psi, vec4(1e-37))),
                      greaterThan(psi, vec4(0.0)));
}
