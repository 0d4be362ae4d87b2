// The exposed float frame (sky, sun, stars) to the screen: tone curve and sRGB encoding
// (the rest of render/tonemap.tonemap and to_srgb8). Alpha 0 marks pixels outside the lens.

uniform sampler2D u_frame;
uniform int u_operator;
out vec4 frag_colour;

void main() {
    vec4 exposed = texelFetch(u_frame, ivec2(gl_FragCoord.xy), 0);
    if (exposed.a == 0.0) {
        frag_colour = vec4(0.0, 0.0, 0.0, 1.0);
        return;
    }
    frag_colour = vec4(encode_srgb_transfer(tonemap(exposed.rgb, u_operator, 1.0)), 1.0);
}
