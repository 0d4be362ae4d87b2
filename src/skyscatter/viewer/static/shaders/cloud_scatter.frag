// Copies a refinement level's T and A (cloud_level.frag) to its pixel (cloud_scatter.vert).

uniform highp sampler2D u_level_t;
uniform highp sampler2D u_level_a;

flat in ivec2 cell;

layout(location = 0) out vec4 known_t;
layout(location = 1) out vec4 known_a;

void main() {
    known_t = texelFetch(u_level_t, cell, 0);
    known_a = texelFetch(u_level_a, cell, 0);
}
