// Shared by the programs (inserted after #version and the variant's defines).
const float PI = 3.14159265358979;

// specula's equirectangular convention (raster/src/equirect.rs): the
// centre column looks down -Z, +Y is the top row (v = 0), u grows toward
// +X. The map's rows are uploaded top first, so t = v.
vec2 dir_to_uv(vec3 d) {
    float phi = atan(d.x, -d.z);
    float theta = acos(clamp(d.y / length(d), -1.0, 1.0));
    return vec2(0.5 + phi / (2.0 * PI), theta / PI);
}

// Exposure, Narkowicz's ACES fit per channel, the sRGB encode: what
// specula's post list does before its 8-bit rounding (the framebuffer's
// unorm conversion rounds here).
vec4 display(vec3 radiance, float exposure_scale) {
    vec3 x = min(max(radiance * exposure_scale, vec3(0.0)), vec3(1e18));
    vec3 t = clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
    vec3 lo = 12.92 * t;
    vec3 hi = 1.055 * pow(t, vec3(1.0 / 2.4)) - 0.055;
    return vec4(mix(hi, lo, lessThanEqual(t, vec3(0.0031308))), 1.0);
}
