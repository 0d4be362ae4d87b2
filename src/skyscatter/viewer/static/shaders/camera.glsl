// Camera rays: the GLSL twins of render/camera.py's PerspectiveCamera and FisheyeCamera.
// Pixel (col, row) of a w x h image, row 0 at the top, has its centre at (col + 0.5, row + 0.5);
// gl_FragCoord.y counts from the bottom, so row + 0.5 = h - gl_FragCoord.y.

uniform vec2 u_resolution;       // (w, h) [pixels]
uniform int u_projection;        // PROJECTION_PERSPECTIVE or PROJECTION_FISHEYE
uniform vec2 u_half_extent;      // perspective: (tan(hfov / 2), tan(vfov / 2))
uniform mat3 u_camera_basis;     // perspective: columns right, up, forward (local ENU)
uniform float u_fisheye_theta_max;  // fisheye: zenith angle on the circle [rad]
uniform mat3 u_local_to_world;   // columns east, north, up of the observer (world)

// Image-plane offsets of a pixel centre: perspective (x right, y up) on the plane at unit
// distance (twin of PerspectiveCamera._image_plane); fisheye (u right, v down) in units of
// the circle radius R = min(w, h) / 2 about the image centre (twin of
// FisheyeCamera._normalised_offsets, which is square)
vec2 image_offsets(vec2 frag) {
    vec2 col_row = vec2(frag.x, u_resolution.y - frag.y);
    if (u_projection == PROJECTION_PERSPECTIVE) {
        return vec2((2.0 * col_row.x / u_resolution.x - 1.0) * u_half_extent.x,
                    (1.0 - 2.0 * col_row.y / u_resolution.y) * u_half_extent.y);
    }
    float radius = 0.5 * min(u_resolution.x, u_resolution.y);
    return (col_row - 0.5 * u_resolution) / radius;
}

// Local ENU view direction of a pixel (twin of the cameras' `directions`); w = 0 outside the
// fisheye circle (the valid mask)
vec4 camera_direction(vec2 frag) {
    vec2 p = image_offsets(frag);
    if (u_projection == PROJECTION_PERSPECTIVE) {
        vec3 ray = u_camera_basis * vec3(p.x, p.y, 1.0);
        return vec4(normalize(ray), 1.0);
    }
    float rho = length(p);
    float theta = u_fisheye_theta_max * rho;
    float sin_over_rho = rho > 0.0 ? sin(theta) / rho : u_fisheye_theta_max;
    return vec4(-p.x * sin_over_rho, -p.y * sin_over_rho, cos(theta), rho <= 1.0 ? 1.0 : 0.0);
}

// Continuous (col, row) of a local direction (twin of `direction_to_pixel`); z = 0 when the
// direction is behind a perspective camera
vec3 direction_to_pixel(vec3 dir) {
    if (u_projection == PROJECTION_PERSPECTIVE) {
        vec3 c = transpose(u_camera_basis) * dir;
        if (c.z <= 0.0) return vec3(0.0);
        vec2 xy = c.xy / c.z / u_half_extent;
        return vec3((xy.x + 1.0) * 0.5 * u_resolution.x, (1.0 - xy.y) * 0.5 * u_resolution.y, 1.0);
    }
    float radius = 0.5 * min(u_resolution.x, u_resolution.y);
    float theta = acos(clamp(dir.z, -1.0, 1.0));
    float azimuth = atan(dir.x, dir.y);
    float rho = theta / u_fisheye_theta_max * radius;
    return vec3(0.5 * u_resolution.x - rho * sin(azimuth),
                0.5 * u_resolution.y - rho * cos(azimuth), 1.0);
}

// Solid angle of the pixel whose image offsets are p [sr] (twin of `pixel_solid_angles`)
float pixel_solid_angle(vec2 p) {
    if (u_projection == PROJECTION_PERSPECTIVE) {
        float area = (2.0 * u_half_extent.x / u_resolution.x) * (2.0 * u_half_extent.y / u_resolution.y);
        return area / pow(1.0 + dot(p, p), 1.5);
    }
    float radius = 0.5 * min(u_resolution.x, u_resolution.y);
    float x = u_fisheye_theta_max * length(p);
    float sinc = x > 0.0 ? sin(x) / x : 1.0;
    return u_fisheye_theta_max * u_fisheye_theta_max * sinc / (radius * radius);
}
