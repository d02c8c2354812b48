#version 330 core
// The main pass: vertices are already in world space (placed at load).
uniform mat4 u_viewproj;

in vec3 in_pos;
in vec3 in_nrm;
in vec2 in_uv;
in vec4 in_tan;

out vec3 v_pos;
out vec3 v_nrm;
out vec2 v_uv;
out vec4 v_tan;

void main() {
    v_pos = in_pos;
    v_nrm = in_nrm;
    v_uv = in_uv;
    v_tan = in_tan;
    gl_Position = u_viewproj * vec4(in_pos, 1.0);
}
