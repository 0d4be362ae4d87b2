// One level of the adaptive refinement over the pixels (twin of transport.adaptive_pixels.refine
// with transport.clouds._CloudsOver's march and settle): fragment (i, j) of a compact grid is
// the pixel at column dx + i s, row dy + j s (rows from the top). On the first lattice it is
// marched; later, with CLOUD_SETTLE defined, its two or four neighbours half a spacing away,
// known from earlier levels (u_known_t, u_known_a), give it their mean where all met a cloud or
// all missed and their radiance over its own background (u_behind) agrees within
// REFINE_TOLERANCE in every channel, and that pass marks it (depth 0); the pixels it left
// (neighbours that differ, or one missing: the image's edge, a fisheye's rim) are marched by
// this shader without CLOUD_SETTLE, drawn behind them (viewer.js drawRefinedClouds: the depth
// test rejects the settled ones before they are shaded, so the GPU's threads march only those
// left). viewer.js then puts the grid in its places (cloud_scatter.frag).

uniform ivec3 u_level;  // spacing s, dy, dx

layout(location = 0) out vec4 level_t;  // T (XYZ), hit
layout(location = 1) out vec4 level_a;  // A (XYZ)

// the texel of pixel (col, row)
ivec2 texel_of(ivec2 col_row) {
    return ivec2(col_row.x, int(u_resolution.y) - 1 - col_row.y);
}

bool has_ray(ivec2 col_row) {
    return col_row.x < int(u_resolution.x) && col_row.y < int(u_resolution.y)
           && camera_direction(vec2(texel_of(col_row)) + 0.5).w != 0.0;
}

// twin of _settle_kernels.settle_mean for the target pixel and its `count` neighbours at
// `offsets` (col, row)
bool settle(ivec2 target, ivec2 offsets[4], int count, out vec4 t, out vec4 a) {
    vec3 behind = texelFetch(u_behind, texel_of(target), 0).rgb;
    vec3 low = vec3(1e30);
    vec3 high = vec3(-1e30);
    vec3 total = vec3(0.0);
    vec3 t_sum = vec3(0.0);
    vec3 a_sum = vec3(0.0);
    float hit = 0.0;
    for (int k = 0; k < 4; ++k) {
        if (k >= count) break;
        ivec2 p = target + offsets[k];
        if (!has_ray(p)) return false;
        vec4 t_k = texelFetch(u_known_t, texel_of(p), 0);
        vec3 a_k = texelFetch(u_known_a, texel_of(p), 0).rgb;
        if (k == 0) hit = t_k.a;
        else if (t_k.a != hit) return false;
        vec3 value = t_k.rgb * behind + a_k;
        low = min(low, value);
        high = max(high, value);
        total += value;
        t_sum += t_k.rgb;
        a_sum += a_k;
    }
    if (any(greaterThan(high - low, REFINE_TOLERANCE * abs(total / float(count))))) {
        return false;
    }
    t = vec4(t_sum / float(count), hit);
    a = vec4(a_sum / float(count), 0.0);
    return true;
}

void main() {
    int s = u_level.x;
    int dy = u_level.y;
    int dx = u_level.z;
    ivec2 target = ivec2(dx, dy) + ivec2(gl_FragCoord.xy) * s;
    vec4 local = camera_direction(vec2(texel_of(target)) + 0.5);
#ifdef CLOUD_SETTLE
    gl_FragDepth = 0.0;  // settled: the march's pass leaves it
#endif
    if (local.w == 0.0) {  // no ray (outside a fisheye's circle)
        level_t = vec4(1.0, 1.0, 1.0, 0.0);
        level_a = vec4(0.0);
        return;
    }
#ifdef CLOUD_SETTLE
    ivec2 offsets[4];
    int count = 2;
    if (dx == 0) {
        offsets[0] = ivec2(0, -dy);
        offsets[1] = ivec2(0, dy);
    } else if (dy == 0) {
        offsets[0] = ivec2(-dx, 0);
        offsets[1] = ivec2(dx, 0);
    } else {
        offsets[0] = ivec2(-dx, -dy);
        offsets[1] = ivec2(dx, -dy);
        offsets[2] = ivec2(-dx, dy);
        offsets[3] = ivec2(dx, dy);
        count = 4;
    }
    if (!settle(target, offsets, count, level_t, level_a)) discard;
#else
    vec3 t, a;
    float hit;
    uint index = uint(target.y) * uint(u_resolution.x) + uint(target.x);  // row-major: the jitter
    clouds_over(u_local_to_world * local.xyz, u_sun_direction, 1e30, index, t, a, hit);
    level_t = vec4(t, hit);
    level_a = vec4(a, 0.0);
#endif
}
