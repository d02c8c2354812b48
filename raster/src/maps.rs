//! Texture maps that fill a material's parameters per pixel, and the maps
//! that belong to the material rather than to its model: the normal map
//! (which bends the shading frame), occlusion and emission.
//!
//! A shader builds its parameters per lane in two steps: the material's
//! constants, broadcast ([`specula_core::Brdf::params`]), then each map
//! the material has overwrites its slot lane by lane ([`ParamMaps::fill`]).
//! A material without maps skips the second step, and the shading pass
//! then hands it whole runs of packets at once (shading_pass.rs).
//!
//! The maps follow glTF 2.0's material textures:
//! - `base_color`: RGB multiplies the base colour (sRGB texels);
//! - `metallic_roughness`: B multiplies metallic and G the perceptual
//!   roughness (linear texels; R is unused);
//! - `normal`: a tangent-space normal map, n = normalize((2t − 1) ·
//!   (scale, scale, 1)) in the (tangent, bitangent, normal) frame, where
//!   the tangent runs along +u and the bitangent along +v (v = 0 at the
//!   bottom of the picture, so green is "up" in the image, the OpenGL
//!   convention glTF uses) and a mirrored uv layout flips the bitangent
//!   (the tangent's w);
//! - `occlusion`: R, as 1 + strength · (R − 1), darkens the uniform
//!   environment term only (glTF: it applies to indirect light, not to
//!   the lights);
//! - `emissive`: RGB (sRGB texels) multiplies the material's emissive
//!   colour, added to the reflected radiance;
//! - `vertex_color` (not a texture): the mesh's interpolated vertex
//!   colour multiplies the base colour.
//!
//! and the textures of glTF's material extensions ([`LayerMaps`]), each
//! multiplying its factor as the extension defines it:
//! - KHR_materials_specular: `specular` A multiplies the specular weight
//!   (linear), `specular_color` RGB the specular colour (sRGB texels);
//! - KHR_materials_clearcoat: `clearcoat` R multiplies the clearcoat
//!   weight, `clearcoat_roughness` G its perceptual roughness (linear);
//!   `clearcoat_normal` is a normal map read as `normal` is (same
//!   tangent frame, its own scale) that gives the coat its own normal,
//!   handed to the model in the local frame the base's normal map made.
//!   Without it the coat's normal is the surface's, unmapped even where
//!   `normal` bends the base's (the extension: "no normal mapping is
//!   applied to the clear coat layer, even if normal mapping is applied
//!   to the base material"): `ParamMaps::coat_normal`;
//! - KHR_materials_sheen: `sheen_color` RGB multiplies the sheen colour
//!   (sRGB texels), `sheen_roughness` A its perceptual roughness
//!   (linear).
//!
//! Each map may move its texture over the surface by a [`UvTransform`]
//! (glTF's KHR_texture_transform): the uv and its screen derivatives are
//! transformed before the lookup, so the filter's footprint follows. The
//! tangent frame a normal map is read in stays the mesh's (that of the
//! untransformed uvs), as GPU engines do.

use crate::shader::ShadeInput;
use crate::texture::{Filter, Sampler, Texture};
use specula_core::{LaneParams, Real, Rgb, ShadingFrame, V3};
use std::sync::Arc;

/// An affine map of texture coordinates, applied before a map is sampled:
/// uv' = M·uv + c, each row of `rows` being (M₀, M₁, c) of one output
/// coordinate; uv derivatives are mapped by M alone.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvTransform {
    /// u' = rows\[0\]·(u, v, 1), v' = rows\[1\]·(u, v, 1).
    pub rows: [[f32; 3]; 2],
}

impl UvTransform {
    /// The transformed point.
    #[inline(always)]
    pub(crate) fn apply<R: Real>(&self, uv: [R; 2]) -> [R; 2] {
        self.rows.map(|[a, b, c]| {
            R::splat(a as f64).mul_add(uv[0], R::splat(b as f64).mul_add(uv[1], R::splat(c as f64)))
        })
    }

    /// The transformed direction (a derivative of uv): the linear part.
    #[inline(always)]
    pub(crate) fn apply_vector<R: Real>(&self, d: [R; 2]) -> [R; 2] {
        self.rows
            .map(|[a, b, _]| R::splat(a as f64).mul_add(d[0], R::splat(b as f64) * d[1]))
    }

    /// Every coefficient finite (a check for loaders).
    pub fn is_finite(&self) -> bool {
        self.rows.iter().flatten().all(|c| c.is_finite())
    }
}

/// An image sampled at the surface's uv: what every map holds.
#[derive(Clone, Debug, PartialEq)]
pub struct ColorMap {
    /// At least three channels (linear values).
    pub texture: Arc<Texture>,
    pub sampler: Sampler,
    /// Applied to the surface's uv (and its derivatives) before the
    /// lookup; `None` reads the uv as it is.
    pub transform: Option<UvTransform>,
}

impl ColorMap {
    /// The map's RGB at the packet's uv (its filter's level from the
    /// resolve's analytic derivatives); white where the shader got no
    /// surface.
    #[inline(always)]
    pub(crate) fn sample<R: Real>(&self, input: &ShadeInput<R>) -> Rgb<R> {
        match input.surface {
            Some(_) => {
                let [r, g, b] = self.sample_channels(input);
                V3::new(r, g, b)
            }
            None => Rgb::splat(R::ONE),
        }
    }

    /// The map's alpha (its fourth channel: the texture must have four)
    /// at the packet's uv; one where the shader got no surface.
    #[inline(always)]
    pub(crate) fn sample_alpha<R: Real>(&self, input: &ShadeInput<R>) -> R {
        match input.surface {
            Some(_) => self.sample_channels::<R, 4>(input)[3],
            None => R::ONE,
        }
    }

    /// The first `C` channels at the packet's uv (a surface is required).
    #[inline(always)]
    fn sample_channels<R: Real, const C: usize>(&self, input: &ShadeInput<R>) -> [R; C] {
        let Some(s) = input.surface else {
            return [R::ONE; C];
        };
        match &self.transform {
            None => self.texture.sample(&self.sampler, s.uv, s.duv_dx, s.duv_dy),
            Some(t) => self.texture.sample(
                &self.sampler,
                t.apply(s.uv),
                t.apply_vector(s.duv_dx),
                t.apply_vector(s.duv_dy),
            ),
        }
    }
}

/// A tangent-space normal map and its scale (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct NormalMap {
    pub map: ColorMap,
    /// Scales the perturbation's x and y (glTF `normalTexture.scale`).
    pub scale: f32,
}

/// An occlusion map and its strength (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct OcclusionMap {
    pub map: ColorMap,
    /// 0 = no effect, 1 = the map's full value (glTF
    /// `occlusionTexture.strength`).
    pub strength: f32,
}

/// The textures of glTF's material extensions (module docs), each
/// optional. `specular` and `sheen_roughness` are read in their alpha:
/// their textures have four channels.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LayerMaps {
    pub specular: Option<ColorMap>,
    pub specular_color: Option<ColorMap>,
    pub clearcoat: Option<ColorMap>,
    pub clearcoat_roughness: Option<ColorMap>,
    pub clearcoat_normal: Option<NormalMap>,
    pub sheen_color: Option<ColorMap>,
    pub sheen_roughness: Option<ColorMap>,
}

impl LayerMaps {
    fn maps_mut(&mut self) -> impl Iterator<Item = &mut ColorMap> {
        [
            self.specular.as_mut(),
            self.specular_color.as_mut(),
            self.clearcoat.as_mut(),
            self.clearcoat_roughness.as_mut(),
            self.clearcoat_normal.as_mut().map(|n| &mut n.map),
            self.sheen_color.as_mut(),
            self.sheen_roughness.as_mut(),
        ]
        .into_iter()
        .flatten()
    }

    /// The name of the first map whose slot `params` lacks (glTF's
    /// names), or `None`.
    fn unsupported<R: Real, P: LaneParams<R>>(&self, params: &mut P) -> Option<&'static str> {
        let checks: [(&'static str, bool, bool); 7] = [
            (
                "specularTexture",
                self.specular.is_some(),
                params.specular_mut().is_some(),
            ),
            (
                "specularColorTexture",
                self.specular_color.is_some(),
                params.specular_color_mut().is_some(),
            ),
            (
                "clearcoatTexture",
                self.clearcoat.is_some(),
                params.clearcoat_mut().is_some(),
            ),
            (
                "clearcoatRoughnessTexture",
                self.clearcoat_roughness.is_some(),
                params.clearcoat_roughness_mut().is_some(),
            ),
            (
                "clearcoatNormalTexture",
                self.clearcoat_normal.is_some(),
                params.coat_normal_mut().is_some(),
            ),
            (
                "sheenColorTexture",
                self.sheen_color.is_some(),
                params.sheen_color_mut().is_some(),
            ),
            (
                "sheenRoughnessTexture",
                self.sheen_roughness.is_some(),
                params.sheen_roughness_mut().is_some(),
            ),
        ];
        checks
            .into_iter()
            .find(|(_, map, slot)| *map && !*slot)
            .map(|(name, _, _)| name)
    }

    /// Multiplies the slots that have maps (module docs), per lane.
    #[inline(always)]
    fn fill<R: Real, P: LaneParams<R>>(&self, input: &ShadeInput<R>, params: &mut P) {
        if let (Some(map), Some(k)) = (&self.specular, params.specular_mut()) {
            *k *= map.sample_alpha(input);
        }
        if let (Some(map), Some(c)) = (&self.specular_color, params.specular_color_mut()) {
            *c = c.mul_elem(map.sample(input));
        }
        if let (Some(map), Some(c)) = (&self.clearcoat, params.clearcoat_mut()) {
            *c *= map.sample(input).x;
        }
        if let (Some(map), Some(r)) = (&self.clearcoat_roughness, params.clearcoat_roughness_mut())
        {
            *r *= map.sample(input).y;
        }
        if let (Some(map), Some(c)) = (&self.sheen_color, params.sheen_color_mut()) {
            *c = c.mul_elem(map.sample(input));
        }
        if let (Some(map), Some(r)) = (&self.sheen_roughness, params.sheen_roughness_mut()) {
            *r *= map.sample_alpha(input);
        }
    }
}

/// The maps of one material, each optional (module docs).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ParamMaps {
    /// Multiplies the base colour.
    pub base_color: Option<ColorMap>,
    /// B multiplies metallic, G the perceptual roughness.
    pub metallic_roughness: Option<ColorMap>,
    pub normal: Option<NormalMap>,
    pub occlusion: Option<OcclusionMap>,
    /// Multiplies the material's emissive colour.
    pub emissive: Option<ColorMap>,
    /// The surface's vertex colour ([`crate::fragment::Surface::color`])
    /// multiplies the base colour (glTF's COLOR_0).
    pub vertex_color: bool,
    /// The material extensions' textures; `None` when it has none.
    pub layers: Option<Box<LayerMaps>>,
}

/// Smallest n·wo a normal-mapped shading normal is allowed: the same
/// bend toward the eye as the resolve's (resolve.rs).
const MIN_COS_VIEW: f64 = 0.02;

impl ParamMaps {
    /// No maps: the material's parameters are its constants.
    pub fn is_empty(&self) -> bool {
        self.base_color.is_none()
            && self.metallic_roughness.is_none()
            && self.normal.is_none()
            && self.occlusion.is_none()
            && self.emissive.is_none()
            && !self.vertex_color
            && self.layers.is_none()
    }

    /// Every map, mutably (to set their samplers at once).
    pub(crate) fn maps_mut(&mut self) -> impl Iterator<Item = &mut ColorMap> {
        [
            self.base_color.as_mut(),
            self.metallic_roughness.as_mut(),
            self.normal.as_mut().map(|n| &mut n.map),
            self.occlusion.as_mut().map(|o| &mut o.map),
            self.emissive.as_mut(),
        ]
        .into_iter()
        .flatten()
        .chain(self.layers.iter_mut().flat_map(|l| l.maps_mut()))
    }

    /// Every map's sampler filter set to `filter` (a render that must
    /// match a given GPU setting).
    pub fn force_filter(&mut self, filter: Filter) {
        for m in self.maps_mut() {
            m.sampler.filter = filter;
        }
    }

    /// The name of the first map whose slot `params` does not have, as
    /// scene files write it; `None` when every map has its slot. Checked
    /// once when a material is built, so [`ParamMaps::fill`] never drops
    /// a map. (Normal, occlusion and emissive maps belong to the material
    /// and fit every model.)
    pub(crate) fn unsupported<P: LaneParams<f32>>(&self, mut params: P) -> Option<&'static str> {
        if self.base_color.is_some() && params.base_color_mut().is_none() {
            return Some("base_color_texture");
        }
        if self.vertex_color && params.base_color_mut().is_none() {
            return Some("COLOR_0");
        }
        if self.metallic_roughness.is_some()
            && (params.metallic_mut().is_none() || !params.scale_roughness(1.0))
        {
            return Some("metallic_roughness_texture");
        }
        self.layers
            .as_ref()
            .and_then(|l| l.unsupported(&mut params))
    }

    /// Overwrites the slots of `params` that have maps, per lane, at the
    /// packet's uv.
    #[inline(always)]
    pub fn fill<R: Real, P: LaneParams<R>>(&self, input: &ShadeInput<R>, params: &mut P) {
        if let Some(map) = &self.base_color {
            if let Some(c) = params.base_color_mut() {
                *c = c.mul_elem(map.sample(input));
            }
        }
        if let (true, Some(s)) = (self.vertex_color, input.surface) {
            if let Some(c) = params.base_color_mut() {
                *c = c.mul_elem(s.color);
            }
        }
        if let Some(map) = &self.metallic_roughness {
            let t = map.sample(input);
            if let Some(m) = params.metallic_mut() {
                *m *= t.z;
            }
            params.scale_roughness(t.y);
        }
        if let Some(layers) = &self.layers {
            layers.fill(input, params);
        }
    }

    /// The material has a clearcoat normal map.
    pub(crate) fn has_coat_normal_map(&self) -> bool {
        self.layers
            .as_ref()
            .is_some_and(|l| l.clearcoat_normal.is_some())
    }

    /// The clearcoat's normal in the local frame `frame` (the one
    /// [`ParamMaps::frame`] made for this packet), where the maps make it
    /// differ from the base's: its own normal map's, else the surface's
    /// unmapped normal under a base normal map (module docs); `None`
    /// where the coat's normal is the base's.
    #[inline(always)]
    pub(crate) fn coat_normal<R: Real>(
        &self,
        input: &ShadeInput<R>,
        frame: &ShadingFrame<R>,
    ) -> Option<V3<R>> {
        input.surface?;
        let surface = input.frame();
        match self
            .layers
            .as_ref()
            .and_then(|l| l.clearcoat_normal.as_ref())
        {
            Some(nm) => Some(frame.to_local(bent_normal(nm, input, &surface))),
            None if self.normal.is_some() => Some(frame.to_local(surface.n)),
            None => None,
        }
    }

    /// The factor of the uniform environment term per lane:
    /// 1 + strength · (occlusion − 1); `None` without an occlusion map.
    #[inline(always)]
    pub fn occlusion<R: Real>(&self, input: &ShadeInput<R>) -> Option<R> {
        self.occlusion.as_ref().map(|o| {
            let occ = o.map.sample(input).x;
            R::splat(o.strength as f64).mul_add(occ - R::ONE, R::ONE)
        })
    }

    /// The local shading frame: the surface's, bent by the normal map
    /// where there is one (module docs). The bent normal is kept at
    /// n·wo ≥ 0.02 like the resolve's; the tangent and bitangent are the
    /// surface's made orthogonal to it (Gram–Schmidt, which keeps the
    /// frame's handedness).
    #[inline(always)]
    pub fn frame<R: Real>(&self, input: &ShadeInput<R>) -> ShadingFrame<R> {
        let base = input.frame();
        let (Some(nm), Some(_)) = (&self.normal, input.surface) else {
            return base;
        };
        let n = bent_normal(nm, input, &base);
        let any = ShadingFrame::from_normal(n);
        let tan = (base.t - n * n.dot(base.t)).normalize_or(any.t);
        let bit = (base.b - n * n.dot(base.b) - tan * tan.dot(base.b)).normalize_or(n.cross(tan));
        ShadingFrame { t: tan, b: bit, n }
    }
}

/// The unit world normal a normal map gives in the surface's frame `base`
/// (module docs), kept at n·wo ≥ 0.02 like the resolve's.
#[inline(always)]
fn bent_normal<R: Real>(nm: &NormalMap, input: &ShadeInput<R>, base: &ShadingFrame<R>) -> V3<R> {
    let t = nm.map.sample(input);
    let s = R::splat(nm.scale as f64);
    let two = R::splat(2.0);
    let m = V3::new(
        t.x.mul_add(two, -R::ONE) * s,
        t.y.mul_add(two, -R::ONE) * s,
        t.z.mul_add(two, -R::ONE),
    );
    // A texel of (½, ½, ½) or a zero scale with blue ½ gives m = 0:
    // such a lane keeps the surface normal.
    let n = (base.t * m.x + base.b * m.y + base.n * m.z).normalize_or(base.n);
    let wo = input.frag.wo;
    let cos_v = n.dot(wo);
    let min_cos = R::splat(MIN_COS_VIEW);
    let away = cos_v.lt(min_cos);
    V3::select(away, (n - wo * (cos_v - min_cos)).normalize_or(wo), n)
}
