//! A material's alpha and what it does to coverage (glTF 2.0 `alphaMode`).
//!
//! The alpha of a fragment is `factor` × the alpha map's texel alpha
//! (channel 3, linear: 8-bit alpha is never sRGB-decoded) × the vertex
//! colour's alpha (glTF's COLOR_0) where the material reads it:
//! [`MaterialAlpha::alpha`].
//!
//! - [`AlphaMode::Mask`]: a sample is covered only where alpha ≥ the
//!   cutoff. The test runs in the visibility pass, per sample, before
//!   anything is shaded (`scan::scan_triangle_masked`), so supersampling
//!   antialiases a cutout's edges, and the shadow maps' depth passes run
//!   the same test (a masked surface casts the shadow of its cutout). The
//!   alpha there is computed as the shading pass computes it: the same
//!   perspective-correct uv and its analytic screen derivatives at the
//!   sample ([`AlphaInputs::at`], checked against the resolve's surface in
//!   tests), the same sampler and filter, so the mip level is the one the
//!   shading of that sample would read (for a shadow map, the level of
//!   the map's own texel footprint).
//! - [`AlphaMode::Blend`]: the surface draws nothing into the visibility
//!   buffer; after the opaque frame is shaded it is composited over it
//!   (`blend.rs`).

use crate::maps::ColorMap;
use crate::setup::TriPlanes;
use crate::texture::Filter;
use glam::{Vec2, Vec4};
use specula_core::Real;

/// How alpha decides coverage.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AlphaMode {
    /// Covered where alpha ≥ `cutoff`; shaded as opaque.
    Mask { cutoff: f32 },
    /// Composited "over" the opaque frame, back to front.
    Blend,
}

/// A material's alpha: where it comes from and what it does (module docs).
/// A material without one is opaque (alpha 1).
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialAlpha {
    pub mode: AlphaMode,
    /// Constant factor (glTF's baseColorFactor alpha).
    pub factor: f32,
    /// A map whose channel 3 multiplies the factor (glTF's base colour
    /// texture, read with four channels); a map of fewer channels has
    /// alpha 1.
    pub map: Option<ColorMap>,
    /// The vertex colour's alpha multiplies it.
    pub vertex_alpha: bool,
}

/// What the alpha of a fragment is computed from: its uv with the uv's
/// screen derivatives, and its interpolated vertex-colour alpha.
#[derive(Clone, Copy, Debug)]
pub(crate) struct AlphaInputs<R: Real> {
    pub(crate) uv: [R; 2],
    pub(crate) duv_dx: [R; 2],
    pub(crate) duv_dy: [R; 2],
    pub(crate) vertex_alpha: R,
}

impl<R: Real> AlphaInputs<R> {
    /// The inputs at the sample centres (x + lane + ½, y + ½) of a
    /// triangle with these planes, vertex uvs and vertex alphas: the
    /// perspective-correct barycentrics b = k / Σk and their analytic
    /// derivatives ∂b/∂x = (∂k/∂x − b ∂Σk/∂x) / Σk, with the operations in
    /// the order `ResolveContext::resolve` and `surface` use, so the
    /// values are theirs.
    #[inline(always)]
    pub(crate) fn at(p: &TriPlanes, uvs: [Vec2; 3], alphas: [f32; 3], x: u32, y: u32) -> Self {
        let splat = |c: f32| R::splat(c as f64);
        let px = R::splat(x as f64 + 0.5) + R::lane_index();
        let py = R::splat(y as f64 + 0.5);
        let dx = px - splat(p.origin[0]);
        let dy = py - splat(p.origin[1]);
        let plane = |k: [f32; 3]| splat(k[0]).mul_add(dx, splat(k[1]).mul_add(dy, splat(k[2])));
        let (k1, k2, ks) = (plane(p.k1), plane(p.k2), plane(p.ks));
        let w = ks.rcp();
        let (b1, b2) = (k1 * w, k2 * w);
        let [uv0, uv1, uv2] = uvs;
        let (e1, e2) = (uv1 - uv0, uv2 - uv0);
        let uv = [
            splat(e1.x).mul_add(b1, splat(e2.x).mul_add(b2, splat(uv0.x))),
            splat(e1.y).mul_add(b1, splat(e2.y).mul_add(b2, splat(uv0.y))),
        ];
        let db = |axis: usize, k: [f32; 3], b: R| (splat(k[axis]) - b * splat(p.ks[axis])) * w;
        let d = |axis: usize| {
            let (d1, d2) = (db(axis, p.k1, b1), db(axis, p.k2, b2));
            [
                splat(e1.x).mul_add(d1, splat(e2.x) * d2),
                splat(e1.y).mul_add(d1, splat(e2.y) * d2),
            ]
        };
        let [a0, a1, a2] = alphas;
        let vertex_alpha = splat(a1 - a0).mul_add(b1, splat(a2 - a0).mul_add(b2, splat(a0)));
        AlphaInputs {
            uv,
            duv_dx: d(0),
            duv_dy: d(1),
            vertex_alpha,
        }
    }
}

impl MaterialAlpha {
    /// Whether computing the alpha reads the surface (uv or vertex colour).
    pub(crate) fn needs_surface(&self) -> bool {
        self.map.is_some() || self.vertex_alpha
    }

    /// The alpha of every fragment when nothing per pixel feeds it (no map
    /// with an alpha channel, no vertex alpha): the factor.
    pub(crate) fn constant(&self) -> Option<f32> {
        let map_alpha = self.map.as_ref().is_some_and(|m| m.texture.channels() >= 4);
        (!map_alpha && !self.vertex_alpha).then_some(self.factor)
    }

    /// factor × map alpha × vertex alpha per lane (module docs).
    #[inline(always)]
    pub(crate) fn alpha<R: Real>(&self, i: &AlphaInputs<R>) -> R {
        let mut a = R::splat(self.factor as f64);
        if let Some(map) = &self.map {
            if map.texture.channels() >= 4 {
                let t = &map.texture;
                let [_, _, _, ta] = match &map.transform {
                    None => t.sample::<R, 4>(&map.sampler, i.uv, i.duv_dx, i.duv_dy),
                    Some(x) => t.sample::<R, 4>(
                        &map.sampler,
                        x.apply(i.uv),
                        x.apply_vector(i.duv_dx),
                        x.apply_vector(i.duv_dy),
                    ),
                };
                a *= ta;
            }
        }
        if self.vertex_alpha {
            a *= i.vertex_alpha;
        }
        a
    }

    /// This alpha with its map sampled with `filter` (`--texture-filter`).
    pub(crate) fn with_texture_filter(&self, filter: Filter) -> MaterialAlpha {
        let mut a = self.clone();
        if let Some(m) = &mut a.map {
            m.sampler.filter = filter;
        }
        a
    }
}

/// The alpha inputs of a scene triangle's vertices: uvs (zero where the
/// scene has none) and vertex-colour alphas (1 where it has none).
#[inline]
pub(crate) fn vertex_inputs(uvs: &[Vec2], colors: &[Vec4], tri: [u32; 3]) -> ([Vec2; 3], [f32; 3]) {
    let uv = tri.map(|i| uvs.get(i as usize).copied().unwrap_or(Vec2::ZERO));
    let a = tri.map(|i| colors.get(i as usize).map_or(1.0, |c| c.w));
    (uv, a)
}
