// The viewer's frame: one camera ray per pixel, the sky (and ground) from the tables, the
// clouds in front (clouds.glsl), the sun disk (all in CIE XYZ), linear sRGB, exposure and tone
// mapping (render/scene.py's render_sky + api.save_image's PNG path). The clouds' code is
// compiled only where CLOUDS is defined: present in a clear frame's program, it cost that frame
// its registers (2.2 times its GPU time). With CLOUDS_REFINED (viewer.js "cloud_final") the
// clouds come from the adaptive refinement's textures (L = T L_behind + A), else each pixel
// marches them ("cloudy_sky", without float render targets). With FAST_MODEL (viewer.js
// "fast_sky") the clear sky comes from the fast model's LUTs (fast_model.glsl) instead of the
// tables. u_camera_position and u_sun_direction (world) are declared in clouds.glsl.

uniform float u_exposure;        // exposure_scale(EV100, compensation)
// the sun's light at a date's distance over the config's, in stops (0 without a date:
// /api/sky's sun_light_scale, as render --time scales the sky); not the disk's radiance
uniform float u_sun_light_stops;
uniform int u_operator;
uniform int u_output;            // OUTPUT_DISPLAY, OUTPUT_METER or OUTPUT_EXPOSED
uniform vec3 u_sun_disk[SUN_DISK_SAMPLES];  // XYZ disk radiance at cos(limb) = 0 .. 1
uniform float u_sun_solid_angle; // [sr]

out vec4 frag_colour;

// Limb-darkened disk radiance at cos(limb) (twin of Star.disk_radiance, linear between samples)
vec3 sun_disk_radiance(float cos_limb) {
    float f = clamp(cos_limb, 0.0, 1.0) * float(SUN_DISK_SAMPLES - 1);
    int i = min(int(f), SUN_DISK_SAMPLES - 2);
    return mix(u_sun_disk[i], u_sun_disk[i + 1], f - float(i));
}

// The sun disk seen along the local direction `dir` of pixel `frag` (twin of add_sun_disk):
// a disk smaller than SPLAT_PIXELS pixels puts its whole irradiance into the pixel holding its
// centre; a larger one is drawn limb-darkened pixel by pixel
vec3 sun_disk(vec2 frag, vec3 dir, vec3 sun_local, vec3 transmittance) {
    vec3 centre = direction_to_pixel(sun_local);
    if (centre.z == 0.0) return vec3(0.0);
    vec2 sun_pixel = floor(centre.xy);
    vec2 col_row = vec2(frag.x, u_resolution.y - frag.y);
    float omega = pixel_solid_angle(image_offsets(vec2(sun_pixel.x + 0.5,
                                                       u_resolution.y - sun_pixel.y - 0.5)));
    bool inside_image = all(greaterThanEqual(sun_pixel, vec2(0.0)))
                        && all(lessThan(sun_pixel, u_resolution));
    if (inside_image && omega * SPLAT_PIXELS > u_sun_solid_angle) {
        if (all(equal(floor(col_row), sun_pixel))) {
            return u_sun_irradiance * transmittance / omega;
        }
        return vec3(0.0);
    }
    float cos_angle = clamp(dot(dir, sun_local), -1.0, 1.0);
    if (cos_angle <= cos(u_sun_angular_radius)) return vec3(0.0);
    float sin_ratio = sqrt(1.0 - cos_angle * cos_angle) / sin(u_sun_angular_radius);
    return sun_disk_radiance(sqrt(clamp(1.0 - sin_ratio * sin_ratio, 0.0, 1.0))) * transmittance;
}

void main() {
    vec4 local = camera_direction(gl_FragCoord.xy);
    if (local.w == 0.0) {  // outside the fisheye circle; alpha 0 marks it for the composite
        frag_colour = vec4(0.0);
        return;
    }
    vec3 dir = u_local_to_world * local.xyz;
#if defined(CLOUDS_REFINED)
    ivec2 texel = ivec2(gl_FragCoord.xy);
    vec3 radiance = max(texelFetch(u_known_t, texel, 0).rgb * texelFetch(u_behind, texel, 0).rgb
                        + texelFetch(u_known_a, texel, 0).rgb, vec3(0.0));
#elif defined(CLOUDS)
    // the pixel's row-major index: the march's jitter, as the CPU renderer numbers it
    uint row = uint(u_resolution.y - gl_FragCoord.y);
    uint index = row * uint(u_resolution.x) + uint(gl_FragCoord.x);
    vec3 radiance = clouds_in_front(dir, u_sun_direction,
                                    radiance_behind_clouds(dir, u_sun_direction), 1e30, index);
#elif defined(FAST_MODEL)
    vec3 radiance = fast_sky_radiance(u_camera_position, dir, u_sun_direction);
#else
    vec3 radiance = sky_radiance(u_camera_position, dir, u_sun_direction, 1.0);
#endif
    radiance *= exp2(u_sun_light_stops);
#ifdef FAST_MODEL
    vec3 transmittance = fast_sun_transmittance(u_camera_position, u_sun_direction);
#else
    vec3 transmittance = sun_transmittance(u_camera_position, u_sun_direction);
#endif
    if (any(greaterThan(transmittance, vec3(0.0)))) {
        vec3 sun_local = transpose(u_local_to_world) * u_sun_direction;
        vec3 disk = sun_disk(gl_FragCoord.xy, local.xyz, sun_local, transmittance);
#ifdef CLOUDS
        if (any(greaterThan(disk, vec3(0.0)))) {  // behind the clouds
            disk *= cloud_transmittance(vec3(0.0), u_sun_direction, 1e30);
        }
#endif
        radiance += disk;
    }
    if (u_output == OUTPUT_METER) {  // luminance [cd m^-2] and whether the pixel looks up
        frag_colour = vec4(radiance.y, local.z > 0.0 ? 1.0 : 0.0, 0.0, 1.0);
        return;
    }
    if (u_output == OUTPUT_EXPOSED) {  // exposed linear sRGB into the float frame (+ stars)
        frag_colour = vec4(clamp(XYZ_TO_SRGB * radiance * u_exposure, -HALF_MAX, HALF_MAX), 1.0);
        return;
    }
    vec3 display = tonemap(XYZ_TO_SRGB * radiance, u_operator, u_exposure);
    frag_colour = vec4(encode_srgb_transfer(display), 1.0);
}
