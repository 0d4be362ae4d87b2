// The radiance behind the clouds of each pixel (clouds.glsl radiance_behind_clouds), for the
// adaptive refinement (cloud_level.frag settles on it) and the frame (main.frag with
// CLOUDS_REFINED); 0 outside a fisheye's circle.

out vec4 behind;

void main() {
    vec4 local = camera_direction(gl_FragCoord.xy);
    behind = local.w == 0.0 ? vec4(0.0)
           : vec4(radiance_behind_clouds(u_local_to_world * local.xyz, u_sun_direction), 1.0);
}
