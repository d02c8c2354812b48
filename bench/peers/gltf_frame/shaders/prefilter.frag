// One face of one level of the prefiltered chain (at load, not timed):
// the GGX lobe's mean radiance around the texel's direction with
// n = v = r [Karis13], each sample weighted by the lobe's masking G1(l)
// (its weight with v = n) and read from the source mip whose
// texel matches its solid angle [Colbert07]; the mirror level (no
// samples) reads the source bilinearly. specula's chain is the same
// (raster/src/envmap.rs), stored as octahedral maps instead of a cube.
uniform sampler2D t_env;      // the equirectangular map, with mips
uniform sampler2D t_samples;  // one texel per sample: (l in the lobe's frame, lod)
uniform int u_count;          // 0: the mirror level
uniform float u_alpha;        // the level's GGX α
uniform int u_face;           // GL's cube face order: +X, -X, +Y, -Y, +Z, -Z
uniform float u_size;

out vec4 frag;

// The direction of face coordinates (sc, tc) in [-1, 1], as GL's cube
// map lookup defines them (the inverse of its face selection).
vec3 face_dir(int face, float sc, float tc) {
    if (face == 0) return vec3(1.0, -tc, -sc);
    if (face == 1) return vec3(-1.0, -tc, sc);
    if (face == 2) return vec3(sc, 1.0, tc);
    if (face == 3) return vec3(sc, -1.0, -tc);
    if (face == 4) return vec3(sc, -tc, 1.0);
    return vec3(-sc, -tc, -1.0);
}

void main() {
    vec2 st = gl_FragCoord.xy / u_size * 2.0 - 1.0;
    vec3 r = normalize(face_dir(u_face, st.x, st.y));
    if (u_count == 0) {
        frag = vec4(textureLod(t_env, dir_to_uv(r), 0.0).rgb, 1.0);
        return;
    }
    vec3 up = abs(r.y) < 0.999 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0);
    vec3 t = normalize(cross(up, r));
    vec3 b = cross(r, t);
    vec3 sum = vec3(0.0);
    float wsum = 0.0;
    for (int i = 0; i < u_count; i++) {
        vec4 s = texelFetch(t_samples, ivec2(i, 0), 0);
        vec3 l = t * s.x + b * s.y + r * s.z;
        // G1(l) = 1 / (1 + Λ(n·l)), Λ(μ) = (√(α² + (1 − α²) μ²) / μ − 1) / 2.
        float a2 = u_alpha * u_alpha;
        float lambda = (sqrt(a2 + (1.0 - a2) * s.z * s.z) / s.z - 1.0) * 0.5;
        float w = 1.0 / (1.0 + lambda);
        sum += textureLod(t_env, dir_to_uv(l), s.w).rgb * w;
        wsum += w;
    }
    frag = vec4(sum / wsum, 1.0);
}
