// The glTF material (Appendix B with KHR_materials_ior, _specular,
// _clearcoat and _sheen) under a directional and a point light, each
// with 3x3 bilinear PCF, and the environment map by the split sum.
// The formulas are those of specula's `gltf` model
// (core/src/models/gltf.rs, docs/scenes.md "gltf"):
//
//   specular_brdf = D_GGX V_GGX (height-correlated Smith), α = roughness²;
//   w = (1 − |V·H|)⁵;  F_s = F0 + (F90 − F0) w,  G = G0 + (G90 − G0) w;
//   F0 = (1 − m) k f0c + m base,  F90 = (1 − m) k + m,  f0c = min(r0(ior) specular_colour, 1);
//   G0 = k max(f0c), G90 = k (the normative fresnel_mix);
//   base = F_s D V + (1 − G)(1 − m) base/π;
//   sheen: sheen_colour D_charlie V_charlie + base · max(0, 1 − max(sheen_colour) max(E(μo), E(μi)));
//   clearcoat: (1 − c F_c) · that + c F_c D V(α_c) about the coat's normal,
//              F_c = 0.04 + 0.96 (1 − V·N_c)⁵, times (N_c·L)/(N·L) where N_c ≠ N.
//
// A material's layers and textures are compile-time switches (one program
// per material, as GPU engines build shader variants), so each pixel reads
// exactly the textures its material has, as specula's maps do:
//   BASE_TEX, MR_TEX, NORMAL_TEX, COAT (+ COAT_TEX, COAT_ROUGH_TEX,
//   COAT_NORMAL_TEX), COAT_OWN_NORMAL, SHEEN (+ SHEEN_COLOR_TEX,
//   SHEEN_ROUGH_TEX), SPEC_TEX, SPEC_COLOR_TEX.

in vec3 v_pos;
in vec3 v_nrm;
in vec2 v_uv;
in vec4 v_tan;

out vec4 frag;

uniform vec3 u_eye;
uniform float u_exposure_scale;

// The material's factors.
uniform vec3 u_base_color;
uniform float u_metallic;
uniform float u_roughness;
uniform float u_r0;              // ((ior − 1)/(ior + 1))²
uniform float u_specular;
uniform vec3 u_specular_color;
uniform float u_clearcoat;
uniform float u_clearcoat_roughness;
uniform vec3 u_sheen_color;
uniform float u_sheen_roughness;
uniform float u_normal_scale;
uniform float u_coat_normal_scale;

uniform sampler2D t_base_color;
uniform sampler2D t_metallic_roughness;
uniform sampler2D t_normal;
uniform sampler2D t_clearcoat;
uniform sampler2D t_clearcoat_roughness;
uniform sampler2D t_clearcoat_normal;
uniform sampler2D t_sheen_color;
uniform sampler2D t_sheen_roughness;
uniform sampler2D t_specular;
uniform sampler2D t_specular_color;

// The lights.
uniform vec3 u_sun_to_light;
uniform vec3 u_sun_irradiance;
uniform vec3 u_point_pos;
uniform vec3 u_point_intensity;

// Shadows: biases in texels at the shaded point (docs/scenes.md "Shadows").
uniform float u_bias;
uniform float u_normal_bias;
uniform float u_filter_radius;
// The sun's orthographic map: world -> clip (xy across, z its depth
// (d − near)/span mapped to [-1, 1]); d = p·axis.
uniform sampler2DShadow t_sun_shadow;
uniform mat4 u_sun_clip;
uniform vec3 u_sun_axis;
uniform float u_sun_texel;       // world size of a texel
uniform float u_sun_near;
uniform float u_sun_span;
uniform vec2 u_sun_texel_uv;     // one texel in the map's uv
// The point light's six faces in one atlas (3 x 2 tiles): world -> each
// face's clip space, its w the depth along the face's axis.
uniform sampler2DShadow t_point_shadow;
uniform mat4 u_face_clip[6];
uniform float u_face_texel;      // world size of a texel at unit depth
uniform float u_face_near;
uniform vec2 u_face_texel_uv;    // one face texel in the atlas's uv

// The environment: E(n)/π in SH9, the prefiltered chain (level k at
// perceptual roughness k/5), the split-sum albedo table (A, B, C) and the
// sheen albedo tables (E, K).
uniform vec3 u_sh[9];
uniform samplerCube t_prefiltered;
uniform sampler2D t_dfg;
uniform sampler2D t_sheen_lut;

const float ALPHA_MIN = 1e-3;
const float COS_FLOOR = 1e-7;
const float MIN_COS_VIEW = 0.02;
const float DFG_N = 32.0;
const float DFG_MU_LO = 1.0 / 64.0;
const float SHEEN_MU_N = 64.0;
const float SHEEN_R_N = 32.0;

float pow5(float x) { float x2 = x * x; return x2 * x2 * x; }
float max3(vec3 c) { return max(c.r, max(c.g, c.b)); }

// A normal kept at n·v >= 0.02, as specula's resolve and normal maps keep it.
vec3 facing(vec3 n, vec3 v) {
    float c = dot(n, v);
    return c < MIN_COS_VIEW ? normalize(n - v * (c - MIN_COS_VIEW)) : n;
}

// A tangent-space normal map's texel in the frame (t, b, n).
vec3 mapped_normal(vec3 texel, float scale, vec3 t, vec3 b, vec3 n, vec3 v) {
    vec3 m = (texel * 2.0 - 1.0) * vec3(scale, scale, 1.0);
    return facing(normalize(t * m.x + b * m.y + n * m.z), v);
}

// ---- Tables --------------------------------------------------------------

// Nodes on both ends of each axis: a coordinate in [0, 1] to texture uv.
vec2 node_uv(vec2 x, vec2 n) { return (clamp(x, 0.0, 1.0) * (n - 1.0) + 0.5) / n; }

// (A, B, C) at GGX α and view cosine μ (axes: μ linear from 1/64, √α).
vec3 dfg(float alpha, float mu) {
    return texture(t_dfg, node_uv(vec2((mu - DFG_MU_LO) / (1.0 - DFG_MU_LO), sqrt(alpha)), vec2(DFG_N))).rgb;
}

// (E, K) of the sheen lobe at μ and sheen roughness (both axes √).
vec2 sheen_lut(float mu, float roughness) {
    vec2 x = sqrt(vec2(clamp(mu, 0.0, 1.0), roughness));
    return texture(t_sheen_lut, node_uv(x, vec2(SHEEN_MU_N, SHEEN_R_N))).rg;
}

// ---- Lobes ---------------------------------------------------------------

// D V of GGX at α: cos²θh, the two cosines and the view's Smith root.
float dv_ggx(float alpha, float nh2, float nl, float nv, float smith_o) {
    float a2 = alpha * alpha;
    float t = nh2 * (a2 - 1.0) + 1.0;
    float d = a2 / (PI * t * t);
    float smith_i = sqrt(nl * nl * (1.0 - a2) + a2);
    return d * 0.5 / (nv * smith_i + nl * smith_o);
}

float smith_root(float alpha, float c) { float a2 = alpha * alpha; return sqrt(c * c * (1.0 - a2) + a2); }

// Charlie sheen: D and the fitted Λ [Conty17; KhrSheen].
float d_charlie(float alpha, float sin2_h) {
    float inv = 1.0 / alpha;
    return (2.0 + inv) * exp(log(max(sin2_h, 1e-30)) * inv * 0.5) / (2.0 * PI);
}

float l_sheen(float x, float t) {
    float a = mix(21.5473, 25.3245, t), b = mix(3.82987, 3.32435, t), c = mix(0.19823, 0.16801, t);
    float d = mix(-1.97760, -1.27393, t), e = mix(-4.32054, -4.85967, t);
    return a / (1.0 + b * exp(c * log(max(x, 1e-30)))) + d * x + e;
}

float lambda_sheen(float alpha, float c) {
    float t = (1.0 - alpha) * (1.0 - alpha);
    return exp(c < 0.5 ? l_sheen(c, t) : 2.0 * l_sheen(0.5, t) - l_sheen(1.0 - c, t));
}

// What a pixel's parameters and view determine, before any light.
struct Pixel {
    vec3 n, v;            // the (mapped) shading normal, the view
    float nv, alpha, smith_o;
    vec3 f0; float f90;
    vec3 g0, g90;
    vec3 diffuse;         // (1 − m) base
    float coat_alpha, coat_nv, coat_smith_o, coat_weight;
    vec3 nc;              // the coat's normal
    vec3 sheen_color; float sheen_max, sheen_alpha, sheen_roughness, sheen_e_o, sheen_lambda_o;
};

// f(l, v) · (n·l) for a unit direction toward the light.
vec3 f_cos(Pixel p, vec3 l) {
    float nl_raw = dot(p.n, l);
    float nl = max(nl_raw, COS_FLOOR);
    vec3 s = l + p.v;
    float len2 = dot(s, s);
    float w = pow5(clamp(1.0 - 0.5 * sqrt(len2), 0.0, 1.0));  // V·H = |l + v| / 2
    float ns = dot(p.n, s);
    float nh2 = ns * ns / len2;
    float dv = dv_ggx(p.alpha, nh2, nl, p.nv, p.smith_o);
    vec3 f = mix(p.f0, vec3(p.f90), w) * dv + (1.0 - mix(p.g0, p.g90, w)) * p.diffuse / PI;
#ifdef SHEEN
    float e_i = sheen_lut(nl, p.sheen_roughness).x;
    float scale = max(1.0 - p.sheen_max * max(e_i, p.sheen_e_o), 0.0);
    float dv_s = d_charlie(p.sheen_alpha, 1.0 - nh2)
        / ((1.0 + lambda_sheen(p.sheen_alpha, nl) + p.sheen_lambda_o) * 4.0 * nl * p.nv);
    f = p.sheen_color * dv_s + f * scale;
#endif
#ifdef COAT
#ifdef COAT_OWN_NORMAL
    float cl = dot(p.nc, l);
    float cli = max(cl, COS_FLOOR);
    float ncs = dot(p.nc, s);
    float dv_about = dv_ggx(p.coat_alpha, ncs * ncs / len2, cli, p.coat_nv, p.coat_smith_o);
    float dv_c = cl > 0.0 ? dv_about * (cli / nl) : 0.0;
#else
    float dv_c = dv_ggx(p.coat_alpha, nh2, nl, p.nv, p.coat_smith_o);
#endif
    f = f * (1.0 - p.coat_weight) + p.coat_weight * dv_c;
#endif
    return nl_raw > 0.0 ? f * nl : vec3(0.0);
}

// ---- Shadows -------------------------------------------------------------

// The mean of 3 x 3 bilinear comparisons spanning ± the filter radius.
float pcf(sampler2DShadow map, vec2 uv, float ref, vec2 texel_uv) {
    vec2 step = texel_uv * u_filter_radius;
    float sum = 0.0;
    for (int j = -1; j <= 1; j++)
        for (int i = -1; i <= 1; i++)
            sum += texture(map, vec3(uv + vec2(i, j) * step, ref));
    return sum / 9.0;
}

float sun_visibility(vec3 p, vec3 n) {
    vec3 q = p + n * (u_normal_bias * u_sun_texel * (1.0 + u_filter_radius));
    vec4 c = u_sun_clip * vec4(q, 1.0);
    if (any(greaterThan(abs(c.xy), vec2(1.0)))) return 1.0;
    float d = dot(q, u_sun_axis) - u_bias * u_sun_texel;
    return pcf(t_sun_shadow, c.xy * 0.5 + 0.5, (d - u_sun_near) / u_sun_span, u_sun_texel_uv);
}

float point_visibility(vec3 p, vec3 n) {
    // The face of the largest coordinate of the offset (specula's order:
    // +x, −x, +y, −y, +z, −z), picked by the point before its bias.
    vec3 o = p - u_point_pos;
    vec3 a = abs(o);
    int face = a.x >= a.y && a.x >= a.z ? (o.x < 0.0 ? 1 : 0)
             : (a.y >= a.z ? (o.y < 0.0 ? 3 : 2) : (o.z < 0.0 ? 5 : 4));
    mat4 m = u_face_clip[face];
    float texel = u_face_texel * max((m * vec4(p, 1.0)).w, u_face_near);
    vec3 q = p + n * (u_normal_bias * texel * (1.0 + u_filter_radius));
    vec4 c = m * vec4(q, 1.0);
    vec2 ndc = c.xy / c.w;
    if (c.w <= 0.0 || any(greaterThan(abs(ndc), vec2(1.0)))) return 1.0;
    float d = c.w - u_bias * texel;
    vec2 tile = vec2(float(face % 3), float(face / 3));
    vec2 uv = (tile + ndc * 0.5 + 0.5) / vec2(3.0, 2.0);
    return pcf(t_point_shadow, uv, 1.0 - u_face_near / d, u_face_texel_uv);
}

// ---- The environment -----------------------------------------------------

vec3 sh_irradiance_over_pi(vec3 n) {
    float c1 = 0.4886025, c2 = 1.0925484;
    vec3 e = u_sh[0] * 0.2820948 + u_sh[1] * (c1 * n.y) + u_sh[2] * (c1 * n.z) + u_sh[3] * (c1 * n.x)
           + u_sh[4] * (c2 * n.x * n.y) + u_sh[5] * (c2 * n.y * n.z)
           + u_sh[6] * (0.31539157 * (3.0 * n.z * n.z - 1.0)) + u_sh[7] * (c2 * n.x * n.z)
           + u_sh[8] * (0.5462742 * (n.x * n.x - n.y * n.y));
    return max(e, vec3(0.0));
}

// The chain's level for a perceptual roughness: 5 r from level 1 up;
// below, the blend of the mirror level and level 1 whose kernel has the
// lobe's spread, x³ (0.7 + 0.3 x), x = 5 r (specula's level_position).
float level_position(float roughness) {
    float f = clamp(roughness * 5.0, 0.0, 5.0);
    return f < 1.0 ? f * f * f * (0.7 + 0.3 * f) : f;
}

// The prefiltered radiance where and as wide as specula's
// prefilter_reading reads it: the mirror direction pulled toward n by
// (0.1 + (1 − μo) + α) times the dominant direction's pull
// [Lagarde14, listing 22], at α × (1 − 0.8 (1 − μo)(1 − α)), not
// narrowed below level 1.
vec3 prefiltered(vec3 n, vec3 v, float roughness) {
    float mu = dot(n, v);
    vec3 r = n * (2.0 * mu) - v;
    float off_normal = 1.0 - clamp(mu, 0.0, 1.0);
    float alpha = roughness * roughness;
    float s = clamp(1.0 - alpha, 0.0, 1.0);
    float t_dom = 1.0 - s * (sqrt(s) + alpha);
    float t = min((0.1 + off_normal + alpha) * t_dom, 1.0);
    vec3 dir = mix(r, n, t);
    float width = 1.0 - 0.8 * off_normal * s;
    float read = max(roughness * sqrt(width), min(roughness, 0.2));
    return textureLod(t_prefiltered, dir, level_position(read)).rgb;
}

// The split sum: the diffuse lobe's albedo on E(n)/π, the rest under the
// coat on the chain at the base's roughness, the coat's albedo on the
// chain at its roughness about its normal.
vec3 environment(Pixel p) {
    vec3 t = dfg(p.alpha, p.nv);
    vec3 specular = p.f0 * t.x + p.f90 * t.y;
    vec3 diffuse = p.diffuse * (1.0 - (p.g0 * (1.0 - t.z) + p.g90 * t.z));
    vec3 under = specular + diffuse;
#ifdef SHEEN
    float scale = max(1.0 - p.sheen_max * p.sheen_e_o, 0.0);
    float k = p.sheen_max * sheen_lut(p.nv, p.sheen_roughness).y;
    under = p.sheen_color * p.sheen_e_o + max(under * scale - (diffuse + specular * p.alpha) * k, 0.0);
#endif
    float keep = 1.0;
#ifdef COAT
    vec3 tc = dfg(p.coat_alpha, min(p.coat_nv, 1.0));
    keep = 1.0 - p.coat_weight;
#endif
    vec3 lit_diffuse = min(diffuse * keep, under * keep);
    vec3 out_e = lit_diffuse * sh_irradiance_over_pi(p.n)
               + (under * keep - lit_diffuse) * prefiltered(p.n, p.v, sqrt(p.alpha));
#ifdef COAT
    out_e += p.coat_weight * (tc.x + tc.y) * prefiltered(p.nc, p.v, sqrt(p.coat_alpha));
#endif
    return out_e;
}

// ---- The pixel -----------------------------------------------------------

void main() {
    vec3 v = normalize(u_eye - v_pos);
    vec3 ng = facing(normalize(v_nrm), v);  // the surface's normal: shadows' bias, an unmapped coat
    Pixel p;
    p.v = v;
    p.n = ng;
#if defined(NORMAL_TEX) || defined(COAT_NORMAL_TEX)
    vec3 tg = normalize(v_tan.xyz - ng * dot(ng, v_tan.xyz));
    vec3 bt = v_tan.w * cross(ng, tg);
#endif
#ifdef NORMAL_TEX
    p.n = mapped_normal(texture(t_normal, v_uv).rgb, u_normal_scale, tg, bt, ng, v);
#endif

    vec3 base = u_base_color;
    float metallic = u_metallic, roughness = u_roughness, k = u_specular;
    vec3 spec_color = u_specular_color;
#ifdef BASE_TEX
    base *= texture(t_base_color, v_uv).rgb;
#endif
#ifdef MR_TEX
    vec3 mr = texture(t_metallic_roughness, v_uv).rgb;
    metallic *= mr.b;
    roughness *= mr.g;
#endif
#ifdef SPEC_TEX
    k *= texture(t_specular, v_uv).a;
#endif
#ifdef SPEC_COLOR_TEX
    spec_color *= texture(t_specular_color, v_uv).rgb;
#endif
    vec3 f0c = min(spec_color * u_r0, vec3(1.0));
    float dk = (1.0 - metallic) * k;
    p.f0 = base * metallic + dk * f0c;
    p.f90 = dk + metallic;
    p.g0 = vec3(k * max3(f0c));
    p.g90 = vec3(k);
    p.diffuse = base * (1.0 - metallic);
    p.alpha = max(roughness * roughness, ALPHA_MIN);
    p.nv = max(dot(p.n, v), COS_FLOOR);
    p.smith_o = smith_root(p.alpha, p.nv);

    p.nc = p.n;
    p.coat_weight = 0.0;
#ifdef COAT
    float cc = u_clearcoat, ccr = u_clearcoat_roughness;
#ifdef COAT_TEX
    cc *= texture(t_clearcoat, v_uv).r;
#endif
#ifdef COAT_ROUGH_TEX
    ccr *= texture(t_clearcoat_roughness, v_uv).g;
#endif
#ifdef COAT_NORMAL_TEX
    p.nc = mapped_normal(texture(t_clearcoat_normal, v_uv).rgb, u_coat_normal_scale, tg, bt, ng, v);
#elif defined(NORMAL_TEX)
    p.nc = ng;  // the extension: no normal mapping on the coat without its own map
#endif
    p.coat_alpha = max(ccr * ccr, ALPHA_MIN);
#ifdef COAT_OWN_NORMAL
    p.coat_nv = max(dot(p.nc, v), COS_FLOOR);
#else
    p.coat_nv = p.nv;
#endif
    p.coat_smith_o = smith_root(p.coat_alpha, p.coat_nv);
    p.coat_weight = cc * (0.04 + 0.96 * pow5(1.0 - min(p.coat_nv, 1.0)));
#endif

#ifdef SHEEN
    p.sheen_color = u_sheen_color;
    p.sheen_roughness = u_sheen_roughness;
#ifdef SHEEN_COLOR_TEX
    p.sheen_color *= texture(t_sheen_color, v_uv).rgb;
#endif
#ifdef SHEEN_ROUGH_TEX
    p.sheen_roughness *= texture(t_sheen_roughness, v_uv).a;
#endif
    p.sheen_max = max3(p.sheen_color);
    p.sheen_alpha = max(p.sheen_roughness * p.sheen_roughness, ALPHA_MIN);
    p.sheen_e_o = sheen_lut(p.nv, p.sheen_roughness).x;
    p.sheen_lambda_o = lambda_sheen(p.sheen_alpha, p.nv);
#endif

    // The two lights, each times its shadow factor, then the map.
    vec3 color = f_cos(p, u_sun_to_light) * u_sun_irradiance * sun_visibility(v_pos, ng);
    vec3 to_point = u_point_pos - v_pos;
    float d2 = max(dot(to_point, to_point), 1e-8);
    color += f_cos(p, to_point * inversesqrt(d2)) * (u_point_intensity / d2) * point_visibility(v_pos, ng);
    color += environment(p);
    frag = display(color, u_exposure_scale);
}
