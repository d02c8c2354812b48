// The map seen where nothing was drawn: drawn last, as a full-screen
// triangle at the far plane that passes the depth test only where the
// depth buffer still holds its clear value. Bilinear on the source map,
// as specula's background.
uniform sampler2D t_env;
uniform vec3 u_forward, u_right, u_up;
uniform vec2 u_tan;        // tan of the half field of view, x and y
uniform vec2 u_size;       // the frame in pixels
uniform float u_exposure_scale;

out vec4 frag;

void main() {
    vec2 ndc = gl_FragCoord.xy / u_size * 2.0 - 1.0;
    vec3 d = u_forward + u_right * (ndc.x * u_tan.x) + u_up * (ndc.y * u_tan.y);
    frag = display(textureLod(t_env, dir_to_uv(d), 0.0).rgb, u_exposure_scale);
}
