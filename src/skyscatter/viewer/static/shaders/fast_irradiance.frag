// The fast model's ground irradiance LUT (fast_model.glsl; our addition to Hillaire's): at
// texel i the sun's cosine mu_s = 2 i / (w - 1) - 1 and the sky's irradiance on the level
// ground, E = integral of L cos(theta) over the upper hemisphere, from the sky's radiance
// (the sun's single scattering with the phase functions and sigma_s Psi_ms, fast_march) on
// FAST_IRRADIANCE_DIRECTIONS directions of equal solid angle (a hemispherical Fibonacci set).

out vec4 frag_colour;

void main() {
    float mu_s = 2.0 * (gl_FragCoord.x - 0.5) / (FAST_IRRADIANCE_SIZE.x - 1.0) - 1.0;
    vec3 sun = vec3(sqrt(max(1.0 - mu_s * mu_s, 0.0)), 0.0, mu_s);
    vec4 irradiance = vec4(0.0);
    const float GOLDEN_ANGLE = 2.39996322972865332;
    for (int k = 0; k < FAST_IRRADIANCE_DIRECTIONS; ++k) {
        float mu = 1.0 - (float(k) + 0.5) / float(FAST_IRRADIANCE_DIRECTIONS);
        float s = sqrt(max(1.0 - mu * mu, 0.0));
        float phi = GOLDEN_ANGLE * float(k);
        vec3 dir = vec3(s * cos(phi), s * sin(phi), mu);
        vec4 through, f_ms;
        irradiance += mu * fast_march(u_bottom_radius, mu, mu_s, dot(dir, sun), u_fast_group,
                                      FAST_MULTIPLE_STEPS, false, through, f_ms);
    }
    frag_colour = irradiance * (2.0 * PI / float(FAST_IRRADIANCE_DIRECTIONS));
}
