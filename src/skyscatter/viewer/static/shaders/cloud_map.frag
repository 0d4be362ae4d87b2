// The clouds' shadow map, one layer a pass (twin of transport._air_shadow_kernels.
// sun_line_water): for the sun-parallel line through texel (i, j), at u, w = corner + (i + 0.5,
// j + 0.5) texel across the sun's beam from the camera, the water [g m^-2] of layer
// u_map_layer towards the sun from where the line leaves each of MAP_LEVELS spheres, four
// levels to an output (viewer.js `drawCloudMap`: the layer's rows of the three textures). Midpoint steps of
// about MAP_STEP_M from the lowest level's exit to the highest's, the water without the detail
// noise's erosion; each level's share read off the running sum, linear within a step.

uniform int u_map_layer;

layout(location = 0) out vec4 water_low;
layout(location = 1) out vec4 water_middle;
layout(location = 2) out vec4 water_high;

// twin of _air_shadow_kernels._exit: where the line o + a s (b = o.s, |o| = r_o) leaves the
// sphere `radius`, or its closest approach to the centre if it passes outside
float line_exit(float b, float r_o, float radius) {
    float disc = b * b - (r_o - radius) * (r_o + radius);
    return disc > 0.0 ? -b + sqrt(disc) : -b;
}

void main() {
    float passed[MAP_LEVELS];
    float across[MAP_LEVELS];  // each level's exit, in steps from the lowest
    vec2 ij = gl_FragCoord.xy - vec2(0.0, float(u_map_layer) * u_map_size.y);  // (i, j) + 0.5
    vec2 uw = u_map_corner + ij * u_map_texel;
    vec3 q = uw.x * u_map_e1 + uw.y * u_map_e2;  // relative to the camera
    vec3 o = u_camera_position + q;
    float r_o = length(o);
    float b = dot(o, u_sun_direction);
    float top = map_level(MAP_LEVELS - 1);
    float total = 0.0;
    for (int k = 0; k < MAP_LEVELS; ++k) passed[k] = 0.0;
    if (b * b - (r_o - top) * (r_o + top) > 0.0) {
        float a_start = line_exit(b, r_o, map_level(0));
        float a_top = line_exit(b, r_o, top);
        int steps = clamp(int(ceil((a_top - a_start) / MAP_STEP_M)), 1, MAP_MAX_STEPS);
        float da = (a_top - a_start) / float(steps);
        for (int k = 0; k < MAP_LEVELS; ++k) {
            across[k] = clamp((line_exit(b, r_o, map_level(k)) - a_start) / da, 0.0,
                              float(steps));
        }
        int next = 0;  // the exits lie in order along the line
        for (int step = 0; step < MAP_MAX_STEPS; ++step) {
            if (step >= steps) break;
            float a = a_start + (float(step) + 0.5) * da;
            float water = cloud_water(u_map_layer, q + a * u_sun_direction, false) * da;
            while (next < MAP_LEVELS && min(int(across[next]), steps - 1) == step) {
                passed[next] = total + (across[next] - float(step)) * water;
                next += 1;
            }
            total += water;
        }
    }
    water_low = total - vec4(passed[0], passed[1], passed[2], passed[3]);
    water_middle = total - vec4(passed[4], passed[5], passed[6], passed[7]);
    water_high = total - vec4(passed[8], passed[9], passed[10], passed[11]);
}
