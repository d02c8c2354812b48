#version 330 core
// One triangle covering the viewport, at depth `u_depth` (NDC).
uniform float u_depth;

void main() {
    vec2 p = vec2(float((gl_VertexID & 1) << 2) - 1.0, float((gl_VertexID & 2) << 1) - 1.0);
    gl_Position = vec4(p, u_depth, 1.0);
}
