// One pixel of a star's 2 x 2 point: its bilinear weight over the pixel's solid angle.

in vec3 v_exposed;
in vec2 v_centre;
out vec4 frag_colour;

void main() {
    vec2 weight = max(1.0 - abs(gl_FragCoord.xy - v_centre), 0.0);
    float omega = pixel_solid_angle(image_offsets(gl_FragCoord.xy));
    frag_colour = vec4(v_exposed * (weight.x * weight.y) / omega, 0.0);
}
