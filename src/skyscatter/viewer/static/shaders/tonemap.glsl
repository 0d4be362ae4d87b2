// Exposure, tone mapping and the sRGB transfer function: the GLSL twin of render/tonemap.py
// (exposure_scale, the OPERATORS) and spectrum/colour.py (encode_srgb_transfer).

// twin of exposure_scale: 2^compensation / (1.2 2^EV100)
float exposure_scale(float ev100, float compensation_ev) {
    return exp2(compensation_ev) / (SATURATION_FACTOR * exp2(ev100));
}

// twin of tonemap (with aces_narkowicz2016, clamp, exponential, reinhard)
vec3 tonemap(vec3 linear_rgb, int operator_index, float exposure) {
    vec3 x = clamp(linear_rgb * exposure, 0.0, 1e30);
    if (operator_index == OPERATOR_ACES) {
        return clamp(x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
    }
    if (operator_index == OPERATOR_EXPONENTIAL) return 1.0 - exp(-x);
    if (operator_index == OPERATOR_REINHARD) return x / (1.0 + x);
    return clamp(x, 0.0, 1.0);
}

// twin of encode_srgb_transfer, for values in [0, 1]
vec3 encode_srgb_transfer(vec3 linear) {
    vec3 curve = 1.055 * pow(linear, vec3(1.0 / 2.4)) - 0.055;
    return mix(curve, 12.92 * linear, lessThanEqual(linear, vec3(SRGB_LINEAR_LIMIT)));
}
