//! The shading pass: per tile, R::LANES pixels per packet; per material
//! present in the packet, the light loop under that material's lane mask.

use crate::resolve::{Fragment, PacketTris, ResolveContext};
use crate::target::{Target, TILE};
use specula_core::light::Light;
use specula_core::{Brdf, BrdfVisitor, Real, Rgb, V3};

/// HDR radiance per pixel, tile-major like the visibility buffer, one plane
/// per channel.
pub struct ColorBuffer {
    pub r: Vec<f32>,
    pub g: Vec<f32>,
    pub b: Vec<f32>,
}

/// Squared distances below this are treated as this, so a light lying on a
/// surface gives a large finite value instead of inf·0 = NaN.
const MIN_DIST2: f64 = 1e-8;

/// Reflected radiance toward `frag.wo` from all lights and the environment.
struct ShadeLights<'a, R: Real> {
    frag: &'a Fragment<R>,
    lights: &'a [Light],
    environment: Option<[f32; 3]>,
}

impl<R: Real> BrdfVisitor for ShadeLights<'_, R> {
    type Output = Rgb<R>;

    #[inline(always)]
    fn visit<B: Brdf>(self, brdf: &B) -> Rgb<R> {
        let f = self.frag;
        let mut acc = Rgb::zero();
        for light in self.lights {
            match light {
                Light::Point {
                    position,
                    intensity,
                } => {
                    let to_light = V3::from_f32(*position) - f.p;
                    let d2 = to_light.length_squared().max(R::splat(MIN_DIST2));
                    let inv_d = d2.rsqrt();
                    let wi = to_light * inv_d;
                    let f_cos = brdf.f_cos(f.n, wi, f.wo);
                    acc += f_cos.mul_elem(V3::from_f32(*intensity)) * (inv_d * inv_d);
                }
                Light::Directional {
                    to_light,
                    irradiance,
                } => {
                    let f_cos = brdf.f_cos(f.n, V3::from_f32(*to_light), f.wo);
                    acc += f_cos.mul_elem(V3::from_f32(*irradiance));
                }
            }
        }
        if let Some(env) = self.environment {
            acc += brdf.albedo(f.n, f.wo).mul_elem(V3::from_f32(env));
        }
        acc
    }
}

/// Shades tile `t` with lane type R, writing its slices of the colour planes.
/// Returns the number of covered pixels.
pub fn shade_tile<R: Real>(
    ctx: &ResolveContext,
    target: &Target,
    t: usize,
    ids: &[u32],
    out: [&mut [f32]; 3],
) -> u64 {
    let scene = ctx.scene;
    let (tx, ty) = target.tile_origin(t);
    let background = scene.environment.unwrap_or(scene.background);
    let [out_r, out_g, out_b] = out;
    let mut covered = 0u64;
    for row in 0..TILE.min((target.height - ty) as usize) {
        let y = ty + row as u32;
        let mut lx = 0;
        while lx < TILE.min((target.width - tx) as usize) {
            let at = row * TILE + lx;
            let tris = PacketTris::new(&ids[at..], R::LANES);
            let mut color: Rgb<R> = Rgb::from_f32(background);
            if tris.n > 0 {
                covered += tris.covered.count_ones() as u64;
                let frag = ctx.resolve::<R>(tx + lx as u32, y, &tris);
                // Shade once per material present, under its lanes' mask.
                let mut done = 0u32;
                for t in 0..tris.n {
                    if done & (1 << t) != 0 {
                        continue;
                    }
                    let m = scene.tri_material[tris.id[t] as usize];
                    let mut group = 0u32;
                    for u in t..tris.n {
                        if scene.tri_material[tris.id[u] as usize] == m {
                            group |= tris.lanes[u];
                            done |= 1 << u;
                        }
                    }
                    let rgb = scene.materials[m as usize].model.visit(ShadeLights {
                        frag: &frag,
                        lights: &scene.lights,
                        environment: scene.environment,
                    });
                    color = Rgb::select(R::mask_from_bits(group), rgb, color);
                }
            }
            color.x.store(&mut out_r[at..]);
            color.y.store(&mut out_g[at..]);
            color.z.store(&mut out_b[at..]);
            lx += R::LANES;
        }
    }
    covered
}
