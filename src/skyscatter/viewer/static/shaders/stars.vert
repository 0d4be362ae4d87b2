// Stars as points (twin of render/stars.add_stars): each star's irradiance above the air, times
// the transmittance along its line of sight, is deposited bilinearly into the four pixels around
// its continuous image position, divided by each pixel's solid angle (stars.frag), added to the
// exposed float frame. Inputs: the star's refracted direction in the site's east-north-up
// frame and its XYZ irradiance [W m^-2 -> cd m^-2 sr ... i.e. lx]. With CLOUDS defined
// (clouds.glsl before this file) the clouds in front dim it too (their transmittance along its
// line of sight, as render/sky_at_time.py's _world_transmittance).

in vec3 a_direction;
in vec3 a_irradiance;
uniform mat3 u_site_to_world;   // columns east, north, up of the site (world)
#ifndef CLOUDS
uniform vec3 u_camera_position; // planet-centred [m] (clouds.glsl declares it)
#endif
uniform float u_exposure;
out vec3 v_exposed;             // exposed linear sRGB irradiance of the star [-]
out vec2 v_centre;              // continuous position in window coordinates [pixels]

void main() {
    vec3 world = u_site_to_world * a_direction;
    vec3 local = transpose(u_local_to_world) * world;
    vec3 pixel = direction_to_pixel(local);
    vec3 transmittance = sun_transmittance(u_camera_position, world);
#ifdef CLOUDS
    if (any(greaterThan(transmittance, vec3(0.0)))) {
        transmittance *= cloud_transmittance(vec3(0.0), world, 1e30);
    }
#endif
    gl_PointSize = 2.0;
    if (pixel.z == 0.0 || a_direction.z <= 0.0 || all(equal(transmittance, vec3(0.0)))) {
        gl_Position = vec4(2.0, 2.0, 2.0, 1.0);  // behind the camera, below the horizon: clipped
        return;
    }
    v_centre = vec2(pixel.x, u_resolution.y - pixel.y);
    v_exposed = XYZ_TO_SRGB * (a_irradiance * transmittance) * u_exposure;
    gl_Position = vec4(2.0 * v_centre / u_resolution - 1.0, 0.0, 1.0);
}
