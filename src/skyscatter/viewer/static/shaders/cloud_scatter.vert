// One refinement level's pixels (cloud_level.frag's compact grid, `u_level_columns` wide) put
// in their places in the image-sized textures: one point a pixel, at column dx + i s, row
// dy + j s (rows from the top)

uniform ivec3 u_level;  // spacing s, dy, dx
uniform int u_level_columns;
uniform vec2 u_resolution;

flat out ivec2 cell;

void main() {
    cell = ivec2(gl_VertexID % u_level_columns, gl_VertexID / u_level_columns);
    vec2 col_row = vec2(u_level.zy + cell * u_level.x) + 0.5;
    vec2 frag = vec2(col_row.x, u_resolution.y - col_row.y);
    gl_Position = vec4(2.0 * frag / u_resolution - 1.0, 0.0, 1.0);
    gl_PointSize = 1.0;
}
