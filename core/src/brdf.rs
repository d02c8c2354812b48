//! The interface every material model implements, and the dispatch from the
//! runtime [`Model`] value to monomorphized kernels.
//!
//! A model is split the way pbrt splits a Material from its BxDF, and
//! Filament its MaterialInputs from its PixelParams:
//!
//! - the model value (`&self`) holds what is fixed for the whole material
//!   by construction: which terms it composes (NDF, Smith, Fresnel kinds)
//!   and the tables built at its parameters (E(μo) at its α, the
//!   compensation slice);
//! - [`Brdf::Params`] holds, per lane, what may differ from pixel to pixel
//!   (base colour, roughness, metallic, …). [`Brdf::params`] broadcasts the
//!   material's constants, the fast path of untextured materials; a shader
//!   with texture maps overwrites lanes of it before shading
//!   ([`LaneParams`]). Each model's docs say which of its parameters are
//!   lanes.
//!
//! Shading is then split in two steps, so that work that depends only on
//! the pixel is done once per packet however many lights there are:
//!
//! 1. [`Brdf::pixel`] derives from the parameters what does not depend
//!    on the view (F0, the diffuse albedo: Filament's PixelParams), and
//!    [`Brdf::prepare_with`] takes that and the view direction `wo` in the
//!    local shading frame ([`ShadingFrame`]: tangent +X, bitangent +Y,
//!    normal +Z) and returns the model's per-pixel BRDF (μo, table lookups
//!    such as E(μo));
//! 2. each light then asks that state for what it needs: a delta light for
//!    f(wi, wo) cos θi at one local direction ([`Brdf::f_cos_local`]), the
//!    uniform environment for the directional albedo
//!    ([`Brdf::albedo_local`]), a polygon light for the integral over the
//!    polygon ([`Brdf::polygon_local`], where the model has one).

use crate::light::PolygonLocal;
use crate::real::{Mask, Real};
use crate::vec3::{Rgb, V3};

/// A directional albedo in parts for environment maps
/// ([`Brdf::env_lobes`]).
#[derive(Clone, Copy, Debug)]
pub struct EnvLobes<R: Real> {
    /// Albedo of the part lit by the irradiance E(n)/π.
    pub diffuse: Rgb<R>,
    /// Albedo of the glossy part, lit by the GGX-prefiltered radiance
    /// around the mirror direction at `roughness`.
    pub specular: Rgb<R>,
    /// Perceptual roughness of the GGX lobe that stands in for the glossy
    /// part (α = roughness²): the model's own for GGX lobes, the GGX
    /// equivalent of another NDF's (ggx_equivalent.rs).
    pub roughness: R,
    /// Albedo of a clearcoat (grey: its Fresnel depends on the view
    /// alone), lit by the prefiltered radiance around the mirror direction
    /// about `coat_normal` at `coat_roughness`; zero for models without one.
    pub coat: R,
    /// Perceptual roughness of the coat's GGX lobe.
    pub coat_roughness: R,
    /// The coat's unit normal in the local frame (+Z, the base's normal,
    /// unless the coat has its own).
    pub coat_normal: V3<R>,
}

impl<R: Real> EnvLobes<R> {
    /// `total` (the directional albedo) split into `diffuse`, capped per
    /// channel at `total`, and the rest as the glossy part at `roughness`;
    /// no coat.
    #[inline(always)]
    pub(crate) fn split(total: Rgb<R>, diffuse: Rgb<R>, roughness: R) -> EnvLobes<R> {
        let diffuse = Rgb::new(
            diffuse.x.min(total.x),
            diffuse.y.min(total.y),
            diffuse.z.min(total.z),
        );
        EnvLobes::new(diffuse, total - diffuse, roughness)
    }

    /// The two parts as given; no coat.
    #[inline(always)]
    pub(crate) fn new(diffuse: Rgb<R>, specular: Rgb<R>, roughness: R) -> EnvLobes<R> {
        EnvLobes {
            diffuse,
            specular,
            roughness,
            coat: R::ZERO,
            coat_roughness: R::ONE,
            coat_normal: V3::new(R::ZERO, R::ZERO, R::ONE),
        }
    }

    /// The parts with a clearcoat of albedo `coat` at `roughness` about
    /// the local unit `normal`.
    #[inline(always)]
    pub(crate) fn with_coat(self, coat: R, roughness: R, normal: V3<R>) -> EnvLobes<R> {
        EnvLobes {
            coat,
            coat_roughness: roughness,
            coat_normal: normal,
            ..self
        }
    }

    /// The whole directional albedo: the parts' sum.
    #[inline(always)]
    pub fn total(&self) -> Rgb<R> {
        self.diffuse + self.specular + Rgb::splat(self.coat)
    }
}

/// Smallest α any model passes to an NDF: below it D(m) is a spike narrower
/// than f32 can resolve at the peak. (Microfacet inputs are clamped to it
/// with a warning where the scene is read.)
pub(crate) const ALPHA_MIN: f32 = 1e-3;

/// Smallest cosine the models divide by: directions at or below the horizon
/// are masked out by `above`, and this floor only keeps those lanes finite.
pub(crate) const COS_FLOOR: f64 = 1e-7;

/// An orthonormal frame per lane: tangent `t` (+X of the local frame),
/// bitangent `b` (+Y) and normal `n` (+Z), right-handed (b = n × t).
#[derive(Clone, Copy, Debug)]
pub struct ShadingFrame<R> {
    pub t: V3<R>,
    pub b: V3<R>,
    pub n: V3<R>,
}

impl<R: Real> ShadingFrame<R> {
    /// Some frame around unit `n`, for isotropic models (any tangent will
    /// do), without branches or normalization. \[Duff17\]:
    /// s = sign(n.z), a = −1/(s + n.z), c = n.x n.y a,
    /// t = (1 + s n.x² a, s c, −s n.x), b = (c, s + n.y² a, −n.y).
    #[inline(always)]
    pub fn from_normal(n: V3<R>) -> ShadingFrame<R> {
        let s = R::select(n.z.ge(R::ZERO), R::ONE, -R::ONE);
        // |s + n.z| ≥ 1, so the reciprocal is always of a normal number.
        let a = -(s + n.z).rcp();
        let c = n.x * n.y * a;
        ShadingFrame {
            t: V3::new((s * n.x * n.x).mul_add(a, R::ONE), s * c, -s * n.x),
            b: V3::new(c, (n.y * n.y).mul_add(a, s), -n.y),
            n,
        }
    }

    /// The frame of unit `n` and a unit tangent `t` orthogonal to it;
    /// `sign` = ±1 flips the bitangent (mirrored uv layouts). The frame is
    /// then left-handed where sign = −1, which is what the texture layout
    /// means; local coordinates stay (t, b, n) components.
    #[inline(always)]
    pub fn from_normal_tangent(n: V3<R>, t: V3<R>, sign: R) -> ShadingFrame<R> {
        ShadingFrame {
            t,
            b: n.cross(t) * sign,
            n,
        }
    }

    /// `v` in local coordinates (components along t, b, n).
    #[inline(always)]
    pub fn to_local(&self, v: V3<R>) -> V3<R> {
        V3::new(v.dot(self.t), v.dot(self.b), v.dot(self.n))
    }
}

/// What every model knows of the view direction, per lane.
#[derive(Clone, Copy, Debug)]
pub struct Outgoing<R: Real> {
    /// Unit view direction in the local frame.
    pub(crate) wo: V3<R>,
    /// μo = cos θo, floored at 1e-7 (see `above`).
    pub(crate) cos_o: R,
    /// wo strictly above the horizon; models give zero in other lanes.
    pub(crate) above: R::Mask,
}

impl<R: Real> Outgoing<R> {
    #[inline(always)]
    pub(crate) fn new(wo: V3<R>) -> Outgoing<R> {
        Outgoing {
            wo,
            cos_o: wo.z.max(R::splat(COS_FLOOR)),
            above: wo.z.gt(R::ZERO),
        }
    }
}

/// The angles every microfacet model starts from, per lane, for one light
/// direction against a prepared view direction (both local).
#[derive(Clone, Copy, Debug)]
pub(crate) struct HalfAngles<R: Real> {
    /// n·wi and n·wo, floored at 1e-7 (see `above`).
    pub(crate) cos_i: R,
    pub(crate) cos_o: R,
    /// Both directions strictly above the horizon; other lanes must be
    /// zeroed by the caller (the floors above only keep them finite).
    pub(crate) above: R::Mask,
    /// cos²θh and sin²θh of the half vector, from the unnormalized sum
    /// (ndf.rs explains why); both carry the same `rcp` rounding (≤ 4e-7),
    /// so their ratio, which shapes D, is exact.
    pub(crate) cos2_h: R,
    pub(crate) sin2_h: R,
    /// cos θd = wi·h, the Fresnel angle.
    pub(crate) cos_d: R,
    /// |wi + wo| = 2 cos θd (see [`crate::fresnel::schlick_weight_half`]).
    pub(crate) len: R,
    /// The unnormalized half vector s ∝ wi + wo (local; rescaled when tiny,
    /// see `new`), |s|² and 1/|s|², for models that need h's direction
    /// (anisotropic NDFs: h = s/|s|). |s|² ≥ [`HALF_LEN2_MIN`] wherever
    /// s ≠ 0 (s = 0 only for opposite directions, which are not `above`).
    pub(crate) s: V3<R>,
    pub(crate) len2: R,
    pub(crate) inv_len2: R,
}

/// [`HalfAngles::new`] rescales a half vector s with |s|² below this to
/// |s|² ∈ [1, 3], so formulas may take |s|⁴ times the angle terms without
/// leaving f32's normal range. Unscaled lanes have |s| ≥ 1e-3: wi and wo
/// more than 0.06° from opposite, rare as both must be above the horizon.
pub(crate) const HALF_LEN2_MIN: f64 = 1e-6;

impl<R: Real> HalfAngles<R> {
    /// From a unit local `wi` and the prepared view direction.
    #[inline(always)]
    pub(crate) fn new(wi: V3<R>, o: &Outgoing<R>) -> HalfAngles<R> {
        Self::from_sum(wi.z, wi + o.wo, o)
    }

    /// [`HalfAngles::new`] at wi = v · inv_len, for an unnormalized `v` and
    /// inv_len = 1/|v|: s = v · inv_len + wo in one fused step (one step
    /// shorter on the light loop's dependency chains, which bound it).
    #[inline(always)]
    pub(crate) fn scaled(v: V3<R>, inv_len: R, o: &Outgoing<R>) -> HalfAngles<R> {
        Self::from_sum(v.z * inv_len, v.mul_add(inv_len, o.wo), o)
    }

    /// From cos θi = wi.z and s = wi + wo.
    #[inline(always)]
    fn from_sum(cos_i: R, s: V3<R>, o: &Outgoing<R>) -> HalfAngles<R> {
        let above = cos_i.gt(R::ZERO) & o.above;
        // s = wi + wo is zero only for opposite directions, which `above`
        // excludes. For unit wi, wo: |s|² = 2 (1 + wi·wo), so
        // cos θd = wi·s / |s| = |s| / 2 — no normalized h needed.
        let len2 = s.length_squared();
        // A nearly opposite grazing pair (wi = [1, 0, 1e-155], wo = [−1, 0,
        // 1e-155] in f64) makes |s|² underflow and 1/|s|² infinite. The
        // angles depend only on s's direction, so such an s is first scaled
        // by 1/max|sₖ| (other lanes are untouched: the factor is exactly 1).
        // Behind a branch taken almost never: done on every light of every
        // packet, the rescale is a visible share of the shading pass. (cos
        // θd by the hardware root, not x·rsqrt(x): see `smith_ggx_root`.)
        let tiny = len2.lt(R::splat(HALF_LEN2_MIN));
        // |s| (the unscaled length) in each branch: the common one then has
        // no multiply by an `unscale` of 1.
        let (s, len2, len) = if tiny.any() {
            let m = s.x.abs().max(s.y.abs()).max(s.z.abs());
            let tiny = tiny & m.gt(R::ZERO);
            let (scale, unscale) = (R::select(tiny, m.rcp(), R::ONE), R::select(tiny, m, R::ONE));
            let s = s * scale;
            let len2 = s.length_squared();
            (s, len2, len2.sqrt() * unscale)
        } else {
            (s, len2, len2.sqrt())
        };
        let inv_len2 = len2.rcp();
        HalfAngles {
            cos_i: cos_i.max(R::splat(COS_FLOOR)),
            cos_o: o.cos_o,
            above,
            cos2_h: s.z * s.z * inv_len2,
            sin2_h: s.x.mul_add(s.x, s.y * s.y) * inv_len2,
            cos_d: len * R::HALF,
            len,
            s,
            len2,
            inv_len2,
        }
    }
}

/// A model's parameters per lane ([`Brdf::Params`]): the slots a texture
/// map may fill. A slot the model does not have answers `None`, and a
/// scene that maps it is refused when it loads.
pub trait LaneParams<R: Real>: Copy {
    /// The base colour, which a base-colour map multiplies texel by texel.
    #[inline(always)]
    fn base_color_mut(&mut self) -> Option<&mut Rgb<R>> {
        None
    }

    /// Metallic, which a metallic-roughness map's blue channel multiplies
    /// (glTF's metallicRoughnessTexture).
    #[inline(always)]
    fn metallic_mut(&mut self) -> Option<&mut R> {
        None
    }

    /// Multiplies the perceptual roughness by `g` per lane (a
    /// metallic-roughness map's green channel), in whatever form the model
    /// stores it; false, and nothing changed, when the model has no
    /// roughness slot.
    #[inline(always)]
    fn scale_roughness(&mut self, _g: R) -> bool {
        false
    }

    /// The specular weight (KHR_materials_specular's specularFactor),
    /// which a specular map's alpha multiplies.
    #[inline(always)]
    fn specular_mut(&mut self) -> Option<&mut R> {
        None
    }

    /// The specular colour (KHR_materials_specular's
    /// specularColorFactor), which a specular colour map multiplies.
    #[inline(always)]
    fn specular_color_mut(&mut self) -> Option<&mut Rgb<R>> {
        None
    }

    /// The clearcoat weight, which a clearcoat map's red channel
    /// multiplies.
    #[inline(always)]
    fn clearcoat_mut(&mut self) -> Option<&mut R> {
        None
    }

    /// The clearcoat's perceptual roughness, which a clearcoat roughness
    /// map's green channel multiplies.
    #[inline(always)]
    fn clearcoat_roughness_mut(&mut self) -> Option<&mut R> {
        None
    }

    /// The clearcoat's unit normal in the local shading frame (+Z: the
    /// base's normal), which the material's normal maps set where they
    /// make the two differ.
    #[inline(always)]
    fn coat_normal_mut(&mut self) -> Option<&mut V3<R>> {
        None
    }

    /// The sheen colour, which a sheen colour map multiplies.
    #[inline(always)]
    fn sheen_color_mut(&mut self) -> Option<&mut Rgb<R>> {
        None
    }

    /// The sheen's perceptual roughness, which a sheen roughness map's
    /// alpha multiplies.
    #[inline(always)]
    fn sheen_roughness_mut(&mut self) -> Option<&mut R> {
        None
    }
}

/// A BRDF in its local shading frame (normal +Z, tangent +X); directions
/// are unit length and point away from the surface, `wi` toward the light,
/// `wo` toward the viewer.
pub trait Brdf: Send + Sync {
    /// The parameters that may vary per pixel, one value per lane (module
    /// docs).
    type Params<R: Real>: LaneParams<R>;

    /// What the model computes once per pixel from its parameters and the
    /// view direction: the pixel's BRDF, stateless from then on.
    type Prepared<R: Real>: Copy;

    /// The model reads the tangent (anisotropic): the shading pass then
    /// builds the frame from the mesh's tangents instead of any frame
    /// around the normal.
    const ANISOTROPIC: bool = false;

    /// The model integrates polygon lights ([`Brdf::polygon_local`]).
    const POLYGON_LIGHTS: bool = false;

    /// What the parameters determine before the view is known (F0, the
    /// diffuse lobe's albedo): made once per packet, or once per run of
    /// packets whose parameters are the material's constants.
    type Pixel<R: Real>: Copy;

    /// The material's constant parameters in every lane.
    fn params<R: Real>(&self) -> Self::Params<R>;

    /// Lane `i` of `params` in f64 (for references integrated per lane).
    fn params_lane<R: Real>(params: &Self::Params<R>, i: usize) -> Self::Params<f64>;

    /// The view-independent part of the pixel's BRDF.
    fn pixel<R: Real>(&self, params: &Self::Params<R>) -> Self::Pixel<R>;

    /// The pixel's BRDF from its [`Brdf::pixel`] and the unit local view
    /// direction.
    fn prepare_with<R: Real>(&self, pixel: &Self::Pixel<R>, wo: V3<R>) -> Self::Prepared<R>;

    /// [`Brdf::prepare_with`] at the material's constant parameters.
    #[inline(always)]
    fn prepare<R: Real>(&self, wo: V3<R>) -> Self::Prepared<R> {
        self.prepare_with(&self.pixel(&self.params()), wo)
    }

    /// f(wi, wo) for a unit local `wi`, no cosine folded in; zero when
    /// either direction is at or below the horizon.
    fn f_local<R: Real>(&self, p: &Self::Prepared<R>, wi: V3<R>) -> Rgb<R>;

    /// [`Brdf::f_local`] at wi = v · inv_len, for an unnormalized local `v`
    /// and inv_len = 1/|v| (a point light's direction): a model may fold
    /// the scale into its first step (`HalfAngles::scaled`).
    #[inline(always)]
    fn f_local_scaled<R: Real>(&self, p: &Self::Prepared<R>, v: V3<R>, inv_len: R) -> Rgb<R> {
        self.f_local(p, v * inv_len)
    }

    /// f(wi, wo) · max(0, cos θi): the reflected radiance per unit radiance
    /// arriving from `wi`.
    #[inline(always)]
    fn f_cos_local<R: Real>(&self, p: &Self::Prepared<R>, wi: V3<R>) -> Rgb<R> {
        self.f_local(p, wi) * wi.z.max(R::ZERO)
    }

    /// Directional albedo ρ(wo) = ∫ f(wi, wo) cos θi dωi over the
    /// hemisphere: the reflected radiance under a uniform white environment
    /// of radiance 1.
    fn albedo_local<R: Real>(&self, p: &Self::Prepared<R>) -> Rgb<R>;

    /// [`Brdf::albedo_local`] split for light from an environment map:
    /// the part lit by the irradiance around the normal, the part lit
    /// by the radiance around the mirror direction, and a clearcoat's part
    /// around its own mirror direction (split sum). The albedos add up to
    /// [`Brdf::albedo_local`], so a uniform map gives
    /// the uniform environment's value. By default all of it is the
    /// diffuse part; models with a glossy lobe say how they split.
    #[inline(always)]
    fn env_lobes<R: Real>(&self, p: &Self::Prepared<R>) -> EnvLobes<R> {
        EnvLobes::new(self.albedo_local(p), Rgb::zero(), R::ONE)
    }

    /// ∫ over the polygon of f(wi, wo) cos θi dωi: the reflected radiance
    /// per unit radiance of a polygon light (vertices in the local frame,
    /// relative to the shading point). Called only for models whose
    /// [`Brdf::POLYGON_LIGHTS`] is true: scenes are checked when they load,
    /// and a polygon light on any other model is an error there. One
    /// light's shorthand for [`Brdf::prepare_polygons`] then
    /// [`Brdf::polygon_local_with`].
    #[inline(always)]
    fn polygon_local<R: Real>(&self, p: &Self::Prepared<R>, poly: &PolygonLocal<R>) -> Rgb<R> {
        self.polygon_local_with(p, &self.prepare_polygons(p), poly)
    }

    /// What the model computes once per pixel for all of its polygon
    /// lights (LTC table lookups, albedo factors); `()` for models without
    /// polygon lights.
    type PolygonPrepared<R: Real>: Copy;

    /// The per-pixel state of polygon lights, from the prepared view.
    /// Separate from [`Brdf::prepare`] so that pixels lit only by point
    /// lights never pay for it: the light loop calls it once per packet,
    /// and only when the scene has polygon lights.
    fn prepare_polygons<R: Real>(&self, p: &Self::Prepared<R>) -> Self::PolygonPrepared<R>;

    /// [`Brdf::polygon_local`] from the state [`Brdf::prepare_polygons`]
    /// made for this pixel.
    #[inline(always)]
    fn polygon_local_with<R: Real>(
        &self,
        _p: &Self::Prepared<R>,
        _pp: &Self::PolygonPrepared<R>,
        _poly: &PolygonLocal<R>,
    ) -> Rgb<R> {
        Rgb::zero()
    }

    /// f(wi, wo) for directions in any frame whose unit normal is `n` (an
    /// isotropic model's value does not depend on the tangent).
    #[inline(always)]
    fn f<R: Real>(&self, n: V3<R>, wi: V3<R>, wo: V3<R>) -> Rgb<R> {
        self.f_in(&ShadingFrame::from_normal(n), wi, wo)
    }

    /// f(wi, wo) for directions given in the frame's own space.
    #[inline(always)]
    fn f_in<R: Real>(&self, frame: &ShadingFrame<R>, wi: V3<R>, wo: V3<R>) -> Rgb<R> {
        let p = self.prepare(frame.to_local(wo));
        self.f_local(&p, frame.to_local(wi))
    }

    /// Directional albedo at `wo`, around unit normal `n`.
    #[inline(always)]
    fn albedo<R: Real>(&self, n: V3<R>, wo: V3<R>) -> Rgb<R> {
        let frame = ShadingFrame::from_normal(n);
        self.albedo_local(&self.prepare(frame.to_local(wo)))
    }
}

/// Code generic over the model: `Model::visit` calls `visit` with the concrete
/// BRDF type, so the per-light loop inside is monomorphized per model and has
/// no dispatch of its own.
pub trait BrdfVisitor {
    type Output;
    fn visit<B: Brdf>(self, brdf: &B) -> Self::Output;
}
