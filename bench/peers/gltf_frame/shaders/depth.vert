#version 330 core
// A shadow map's depth pass: position only, no fragment work beyond depth.
uniform mat4 u_viewproj;
in vec3 in_pos;

void main() {
    gl_Position = u_viewproj * vec4(in_pos, 1.0);
}
