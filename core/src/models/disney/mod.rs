//! Burley's principled BRDF as the WDAS BRDF Explorer's `disney.brdf`
//! defines it (2015 revision: anisotropic Smith GGX masking)   \[Burley12\]
//!
//! f = (1 − metallic) ((1/π) mix(F_d, ss, subsurface) C_d + sheen C_sheen F_H)
//!   + F_s D_s G_s / (4 μi μo)
//!   + ¼ clearcoat F_r D_r G_r / (4 μi μo)
//!
//! - C_d = base_color (linear RGB, like every material here: the Explorer's
//!   gamma decode is not applied); C_tint = C_d / lum(C_d) with
//!   lum = 0.3 r + 0.6 g + 0.1 b (white where lum = 0);
//! - F_d, ss: `diffuse::fd_burley` (F_D90 = ½ + 2 cos²θd roughness) and
//!   `diffuse::f_subsurface_burley`; F_H = (1 − cos θd)⁵;
//!   C_sheen = mix(1, C_tint, sheen_tint);
//! - specular: D_s = `ndf::d_ggx_aniso` with aspect = √(1 − 0.9 anisotropic),
//!   αx = max(0.001, r²/aspect), αy = max(0.001, r² aspect) along the
//!   tangent (+X) and bitangent (+Y); G_s = G1(i) G1(o), separable Smith with
//!   `masking::lambda_ggx_aniso`; F_s = Schlick toward
//!   C_spec0 = mix(0.08 specular mix(1, C_tint, specular_tint), C_d, metallic);
//! - clearcoat: D_r = GTR1 (`ndf::d_gtr`, γ = 1) at α = mix(0.1, 0.001,
//!   clearcoat_gloss); G_r = separable Smith GGX at α = 0.25; F_r = Schlick
//!   with F0 = 0.04.
//!
//! The model adds no formula of its own beyond these compositions.
//!
//! Optional energy compensation adds Kulla–Conty's multiple-scattering lobe
//! to the specular lobe (kulla_conty.rs, the separable GGX table, colour
//! factor from F_avg of C_spec0). The table is isotropic; an anisotropic
//! lobe is indexed at the isotropic-equivalent α = √(αx αy), which is r²
//! whenever neither α hits its 0.001 floor (αx αy = r⁴ for any aspect).
//! A white metal then reflects 1 within 1e-4 for anisotropic = 0; for
//! anisotropic > 0 the loss depends on the view's azimuth, which the
//! isotropic table cannot follow: measured from 0.41 short to 2.2% over
//! (core/tests/disney.rs, `metallic_white_furnace_bounds`).
//!
//! Uniform environment light needs the directional albedo ρ(wo), which for
//! an anisotropic lobe depends on the view's azimuth: it is tabulated per
//! material over μo and cos²φo (φo measured from the tangent; the albedo is
//! even in both local x and y, so cos²φo ∈ [0, 1] covers every azimuth) by
//! quadrature of this same BRDF when the material is built; see
//! [`Disney::albedo_quadrature`].
//!
//! **Polygon lights** (linearly transformed cosines \[Heitz16\], the
//! project's GGX fit in ltc/ggx.rs). Once per pixel, `prepare_polygons`
//! looks up one LTC for the specular lobe (four with clearcoat) and the
//! lobes' albedos; each light then costs one clipped polygon integral for
//! specular and diffuse together, three more for the coat.
//!
//! - Specular: the GGX fit (height-correlated Smith, shared by this
//!   separable lobe as by `microfacet`'s) at the isotropic-equivalent
//!   α = √(αx αy), with the fit's Schlick split F0 (n − n_w) + n_w applied
//!   to C_spec0. √(αx αy) keeps the NDF's peak 1/(π αx αy) and the solid
//!   angle of the highlight (∝ αx αy), so a small light in the mirror
//!   direction gets about the right peak; it is also the α the
//!   Kulla–Conty table is read at. An isotropic lobe cannot follow an
//!   anisotropic one, though (p90 26 %, max 57 % of the albedo at
//!   anisotropic = 1; the RMS α √((αx² + αy²)/2) was no better: p90 15 %,
//!   max 77 %), so anisotropic lobes (`Disney::anisotropic_ltc`) shear
//!   the fit's cosine: the half-vector slopes have covariance
//!   C = [[p, κ], [κ, q]] in the view's frame (x along its azimuth φo:
//!   p = αx² cos²φo + αy² sin²φo, q = αx² + αy² − p, κ = (αy² − αx²)
//!   cos φo sin φo), a small deviation of the half vector moves the
//!   reflected direction by (2 δx, 2 μo δy) in the frame of the mirror
//!   direction, so the lobe is the isotropic one at α_ref mapped by
//!   L = √C / α_ref in the cosine's xy-plane (rows of M⁻¹ times L⁻¹).
//!   α_ref² = μo² αx αy + (1 − μo²) p: the isotropic equivalent at the
//!   normal, where the lobe must not depend on φo, and the α along the
//!   view's plane toward grazing views, whose magnitude n and skew the
//!   fit then supplies. Measured: p90 15 %, max 36 % at anisotropic = 1,
//!   p90 2.7 %, max 15.5 % at 0.5 (core/tests/disney_ltc.rs). Lobes with
//!   αx or αy above the table's α = 1 (rough and strongly anisotropic)
//!   keep the unsheared fit at √(αx αy). (Stretching the polygon by
//!   diag(α/αx, α/αy, 1), the microsurface's stretch invariance, was
//!   tried: it does not commute with reflection, and was worse: max 170 %.)
//! - Clearcoat: GTR1 is not GGX. Its tail falls as 1/sin²θh, not
//!   1/sin⁴θh: half its D cos θh mass lies beyond tan θh = √α, against α
//!   for GGX, so one GGX at the coat's α (or at √α, or at the α of equal
//!   peak) errs by up to 77 % of the coat's albedo (p90 20–35 %). The coat
//!   has its own fit (ltc/coat.rs, `specula fit-ltc-coat`): per (ln α, μo)
//!   a mixture of three linearly transformed cosines Σ wₖ Dₖ fitted to the
//!   coat lobe itself (GTR1, the Smith G at α = 0.25 and the F0 = 0.04
//!   Fresnel all in the fitted shape), times its directional albedo.
//!   Measured on the coat lobe alone (core/tests/disney_ltc.rs,
//!   `coat_ltc_error_by_gloss_and_view`, as a fraction of the coat's
//!   albedo, clearcoat_gloss 0–1): p90 1.1 %, max 7.3 % (gloss 1,
//!   α = 0.001, whose mass spans three decades of tan θh, at θo = 85°);
//!   gloss ≤ 0.75 max 3.6 %; θo ≤ 30° max 1.5 %. Two cosines (one
//!   integral fewer) measured p90 2.0 %, max 13.6 %; the two-GGX
//!   stand-in before them (two GGX fits, whose G and Fresnel are not the
//!   coat's, mixed to GTR1's cumulative distribution) p90 6.2 %,
//!   max 17.4 %. Cost: each cosine is one more clipped polygon integral
//!   per light, so the coat's three make a coated material's polygon
//!   lights markedly dearer than an uncoated one's
//!   (`specula-bench`'s `disney` bench measures it).
//! - Diffuse, subsurface blend and sheen (× (1 − metallic)): the polygon's
//!   exact Lambert form factor times the lobes' directional albedo at μo,
//!   i.e. the lobes replaced by the Lambertian lobe of the same albedo at
//!   this view (exact for a light filling the hemisphere). For fixed
//!   directions F_d and ss are quadratic in roughness, so their albedos
//!   are three μo curves each, plus sheen's (1 − cos θd)⁵: one
//!   process-wide table (`diffuse_albedo_table`, 64 μo × 7, within
//!   2.2e-4 of the model's quadrature) serves every material. Measured:
//!   p90 2.4 %, max 13.5 % (retro-reflection and sheen at grazing views).
//! - Compensation: its lobe as its albedo factor · (1 − E(μo)) times the
//!   form factor, like `microfacet`'s.
//!
//! **Environment maps** (split sum, [`Brdf::env_lobes`]): the diffuse
//! lobes and the compensation lobe on the irradiance, as for polygon
//! lights; the clearcoat's albedo (its own μo table, from the same
//! quadrature as ρ(wo)) on the prefiltered GGX chain at the GGX α whose
//! normals spread like GTR1's (√α_r, ggx_equivalent.rs) about the normal;
//! the rest of ρ(wo), the specular lobe's, on the chain at √(αx αy). The
//! clearcoat is added to the base, not layered over it, so nothing under
//! it is attenuated (as for lights).
//!
//! **Lane parameters** ([`DisneyLaneParams`]): the lobes' colours
//! ((1 − metallic) C_d / π, the sheen colour, C_spec0) and the diffuse
//! lobes' roughness and subsurface, as the kernels read them. No texture
//! map may set them yet: the directional albedo is tabulated per material
//! over all parameters, so a pixel whose parameters differ from the
//! material's would be lit by the environment with the wrong albedo. The
//! specular and clearcoat α, which select tables and LTC forms, are the
//! material's.
//!
//! All lobes together over roughness 0.05–1, metallic 0/1, anisotropic
//! 0/0.5/1, clearcoat 0/1, sheen 0/1: median 0.17 %, p90 3.2 %, max 47 %
//! of the directional albedo (isotropic lobes: p90 2.1 %, max 10.9 %).

use crate::brdf::{Brdf, EnvLobes, HalfAngles, LaneParams, Outgoing, ALPHA_MIN};
use crate::diffuse::{f_subsurface_burley, fd_burley, sheen_burley};
use crate::fresnel::{f_schlick, schlick_weight};
use crate::ggx_equivalent::ggx_equivalent_alpha;
use crate::kulla_conty::KcColor;
use crate::light::PolygonLocal;
use crate::ltc::coat::{self, LtcCoat, ALPHA_HI, ALPHA_LO};
use crate::ltc::ggx::LtcGgx;
use crate::masking::{g1_smith, lambda_ggx, lambda_ggx_aniso};
use crate::models::microfacet::{Compensation, Fresnel, GtrLambda, MicrofacetParams, Ndf, Smith};
use crate::ndf::{d_ggx_aniso, d_gtr};
use crate::quadrature::GaussLegendre;
use crate::real::Real;
use crate::table::{Axis, Nodes, Table1, Table2, Warp};
use crate::vec3::{Rgb, V3};
use std::f64::consts::{FRAC_PI_2, PI, TAU};
use std::sync::OnceLock;

mod albedo;
mod polygons;

pub(crate) use albedo::diffuse_albedo_table;
use albedo::{azimuth_dir, diffuse_albedo_of};
pub use albedo::{diffuse_albedo_coefficients, Lobe};
pub use polygons::DisneyPolygons;

/// The ten parameters and the base colour, with Burley's meanings; the
/// defaults are the BRDF Explorer's.
#[derive(Clone, Debug, PartialEq)]
pub struct DisneyParams {
    /// Linear RGB.
    pub base_color: [f32; 3],
    pub metallic: f32,
    pub subsurface: f32,
    /// 0.08 specular is F0 of the dielectric (0.5 ↔ IOR 1.5).
    pub specular: f32,
    pub specular_tint: f32,
    /// Perceptual roughness; α = roughness².
    pub roughness: f32,
    pub anisotropic: f32,
    pub sheen: f32,
    pub sheen_tint: f32,
    pub clearcoat: f32,
    pub clearcoat_gloss: f32,
}

impl Default for DisneyParams {
    fn default() -> DisneyParams {
        DisneyParams {
            base_color: [0.82, 0.67, 0.16],
            metallic: 0.0,
            subsurface: 0.0,
            specular: 0.5,
            specular_tint: 0.0,
            roughness: 0.5,
            anisotropic: 0.0,
            sheen: 0.0,
            sheen_tint: 0.5,
            clearcoat: 0.0,
            clearcoat_gloss: 1.0,
        }
    }
}

/// Smith α of the clearcoat's masking, fixed by the Explorer.
const CLEARCOAT_G_ALPHA: f64 = 0.25;
/// Normal-incidence reflectance of the clearcoat (IOR 1.5).
const CLEARCOAT_F0: f64 = 0.04;

fn mix(a: f64, b: f64, t: f64) -> f64 {
    a + (b - a) * t
}

impl DisneyParams {
    /// (αx, αy) of the specular lobe (module docs).
    pub fn alphas(&self) -> (f64, f64) {
        let r2 = (self.roughness as f64).powi(2);
        let aspect = (1.0 - 0.9 * self.anisotropic as f64).sqrt();
        (
            (r2 / aspect).max(ALPHA_MIN as f64),
            (r2 * aspect).max(ALPHA_MIN as f64),
        )
    }

    /// C_tint: the base colour with its luminance divided out (hue and
    /// saturation only), white for a black base.
    pub(crate) fn tint(&self) -> [f64; 3] {
        let c = self.base_color.map(|v| v as f64);
        let lum = 0.3 * c[0] + 0.6 * c[1] + 0.1 * c[2];
        if lum > 0.0 {
            c.map(|v| v / lum)
        } else {
            [1.0; 3]
        }
    }

    /// C_spec0, the specular lobe's Schlick F0 per channel.
    pub(crate) fn cspec0(&self) -> [f64; 3] {
        let tint = self.tint();
        let s = 0.08 * self.specular as f64;
        let (st, m) = (self.specular_tint as f64, self.metallic as f64);
        core::array::from_fn(|c| mix(s * mix(1.0, tint[c], st), self.base_color[c] as f64, m))
    }

    /// C_sheen = mix(1, C_tint, sheen_tint).
    pub(crate) fn csheen(&self) -> [f64; 3] {
        self.tint().map(|t| mix(1.0, t, self.sheen_tint as f64))
    }

    /// GTR1 α of the clearcoat.
    pub fn clearcoat_alpha(&self) -> f64 {
        mix(0.1, 0.001, self.clearcoat_gloss as f64)
    }
}

/// What the kernels read, formed once per material in f64 (splat to the
/// lane type per use).
#[derive(Clone, Debug, PartialEq)]
struct Derived {
    /// (1 − metallic) C_d / π.
    diffuse: [f64; 3],
    /// (1 − metallic) sheen C_sheen.
    sheen: [f64; 3],
    cspec0: [f64; 3],
    alpha_x: f64,
    alpha_y: f64,
    roughness: f64,
    subsurface: f64,
    clearcoat_alpha: f64,
    /// ¼ clearcoat.
    clearcoat_weight: f64,
    /// α of the specular lobe's GGX LTC lookup for polygon lights: its
    /// isotropic equivalent √(αx αy) (module docs, "Polygon lights").
    spec_ltc_alpha: f64,
    /// ln α of the clearcoat, where its LTC table is read (ltc/coat.rs),
    /// α clamped into the table's [0.001, 0.1] (a material's own range).
    coat_ln_alpha: f64,
    /// Perceptual roughness of the GGX lobes that stand in for the
    /// specular lobe (at √(αx αy)) and for the clearcoat's GTR1 (its GGX
    /// equivalent, ggx_equivalent.rs) under environment maps.
    env_roughness: f64,
    coat_env_roughness: f64,
}

impl Derived {
    fn new(p: &DisneyParams) -> Derived {
        let m = p.metallic as f64;
        let (alpha_x, alpha_y) = p.alphas();
        let sheen = p.csheen().map(|c| (1.0 - m) * p.sheen as f64 * c);
        Derived {
            diffuse: p.base_color.map(|c| (1.0 - m) * c as f64 / PI),
            sheen,
            cspec0: p.cspec0(),
            alpha_x,
            alpha_y,
            roughness: p.roughness as f64,
            subsurface: p.subsurface as f64,
            clearcoat_alpha: p.clearcoat_alpha(),
            clearcoat_weight: 0.25 * p.clearcoat as f64,
            spec_ltc_alpha: (alpha_x * alpha_y).sqrt(),
            coat_ln_alpha: p.clearcoat_alpha().clamp(ALPHA_LO, ALPHA_HI).ln(),
            env_roughness: (alpha_x * alpha_y).sqrt().min(1.0).sqrt(),
            coat_env_roughness: ggx_equivalent_alpha(Ndf::Gtr { gamma: 1.0 }, p.clearcoat_alpha())
                .sqrt(),
        }
    }
}

#[inline(always)]
fn rgb<R: Real>(c: [f64; 3]) -> Rgb<R> {
    Rgb::new(R::splat(c[0]), R::splat(c[1]), R::splat(c[2]))
}

/// μo nodes of the albedo table: from `MU_LO` to the normal view, even
/// in √((μo − `MU_LO`)/(1 − `MU_LO`)) (dense at grazing). A node at
/// μo = 1, because the albedo of a rough lobe still changes there (a
/// table clamped to its last texel centre reads a rough metal too bright
/// near the normal). Below `MU_LO` (views within 0.02° of grazing) lanes
/// read the first node.
const N_MU: usize = 32;
const MU_LO: f64 = 1.0 / 4096.0;
const MU_AXIS: Axis = Axis::new(N_MU, MU_LO, 1.0, Warp::Sqrt, Nodes::Ends);
/// cos²φo nodes (ends included) for anisotropic lobes; isotropic ones need
/// two equal nodes.
const N_PHI_ANISO: usize = 9;

/// A Disney material: parameters, derived constants, the optional
/// compensation lobe and the directional-albedo table.
#[derive(Clone, Debug, PartialEq)]
pub struct Disney {
    pub params: DisneyParams,
    d: Derived,
    kc: Option<Compensation>,
    /// ρ(wo) per channel over (μo, cos²φo); zeros when built without it.
    albedo: Table2<3>,
    /// The clearcoat lobe's share of ρ(wo) over μo (it does not depend on
    /// the view's azimuth); zeros when built without the albedo table.
    coat_albedo: Table1<1>,
}

/// A Disney material's parameters per lane (module docs, "Lane
/// parameters").
#[derive(Clone, Copy, Debug)]
pub struct DisneyLaneParams<R: Real> {
    /// (1 − metallic) C_d / π.
    pub(crate) diffuse: Rgb<R>,
    /// (1 − metallic) sheen C_sheen.
    pub(crate) sheen: Rgb<R>,
    /// C_spec0, the specular lobe's Schlick F0.
    pub(crate) cspec0: Rgb<R>,
    pub(crate) roughness: R,
    pub(crate) subsurface: R,
}

impl<R: Real> LaneParams<R> for DisneyLaneParams<R> {}

/// Per-pixel state of a Disney material.
#[derive(Clone, Copy)]
pub struct DisneyPrepared<R: Real> {
    pub(crate) o: Outgoing<R>,
    pub(crate) lanes: DisneyLaneParams<R>,
    /// (1 − μo)⁵.
    pub(crate) w_o: R,
    /// Smith G1(o) of the specular and of the clearcoat lobe.
    pub(crate) g1_o: R,
    pub(crate) g1_coat_o: R,
    /// 1 − E(μo) of the compensation lobe (0 without compensation).
    pub(crate) one_minus_e_o: R,
}

/// The lobes of f at one direction pair, each without the horizon mask
/// (the caller selects): what the quadratures integrate one at a time.
#[derive(Clone, Copy, Debug)]
pub struct DisneyLobes<R: Real> {
    /// (1 − metallic)((1/π) mix(F_d, ss, subsurface) C_d + sheen C_sheen F_H).
    pub diffuse: Rgb<R>,
    /// F_s D_s G_s / (4 μi μo), plus the compensation lobe when enabled.
    pub specular: Rgb<R>,
    /// ¼ clearcoat F_r D_r G_r / (4 μi μo) (grey).
    pub clearcoat: R,
}

impl Disney {
    /// Builds the material, with Kulla–Conty compensation of the specular
    /// lobe when `energy_compensation`, and tabulates its directional
    /// albedo (32 μo × 2 azimuth rows, 9 for anisotropic lobes, each entry
    /// a quadrature of a few thousand BRDF evaluations: tens of ms per
    /// material in an optimized build; the 50 materials of
    /// disney-sweep.toml load in about 3 s on 2 busy cores). Parameters
    /// are trusted: the scene reader validates them.
    pub fn new(params: DisneyParams, energy_compensation: bool) -> Disney {
        let mut m = Disney::new_without_table(params, energy_compensation);
        let phi_nodes = if m.d.alpha_x == m.d.alpha_y {
            2
        } else {
            N_PHI_ANISO
        };
        let phi_axis = Axis::new(phi_nodes, 0.0, 1.0, Warp::Linear, Nodes::Ends);
        // The φ-independent lobes once per μ, the specular lobe per node.
        let iso: Vec<([f64; 3], f64)> = (0..N_MU)
            .map(|i| m.isotropic_albedo(MU_AXIS.node(i)))
            .collect();
        m.coat_albedo = Table1::from_nodes(MU_AXIS, iso.iter().map(|i| [i.1 as f32]).collect());
        let rows = (0..phi_nodes)
            .map(|j| {
                (0..N_MU)
                    .map(|i| {
                        let wo = azimuth_dir(MU_AXIS.node(i), phi_axis.node(j));
                        let s = m.specular_albedo(wo);
                        core::array::from_fn(|c| (iso[i].0[c] + s[c]) as f32)
                    })
                    .collect()
            })
            .collect();
        m.albedo = Table2::from_rows(MU_AXIS, phi_axis, rows);
        m
    }

    /// The model without the albedo table (for evaluating f only; its
    /// `albedo_local` is then zero). Cheap to build (the compensation table
    /// is shared per process).
    pub fn new_without_table(params: DisneyParams, energy_compensation: bool) -> Disney {
        // The process-wide tables of polygon lights are built here, once,
        // not inside the shading pass.
        diffuse_albedo_table();
        if params.clearcoat > 0.0 {
            coat::table();
        }
        Disney::bare(params, energy_compensation)
    }

    /// [`Disney::new_without_table`] without touching the process-wide
    /// tables.
    fn bare(params: DisneyParams, energy_compensation: bool) -> Disney {
        let d = Derived::new(&params);
        let kc = energy_compensation.then(|| {
            let alpha = (d.alpha_x * d.alpha_y).sqrt().clamp(ALPHA_MIN as f64, 1.0);
            let p = MicrofacetParams {
                ndf: Ndf::Ggx,
                alpha: alpha as f32,
                smith: Smith::Separable,
                fresnel: Fresnel::Schlick {
                    f0: d.cspec0.map(|c| c as f32),
                },
                diffuse: [0.0; 3],
                gtr_lambda: GtrLambda::Ggx,
            };
            Compensation::new(&p, KcColor::KullaConty)
        });
        let phi = Axis::new(2, 0.0, 1.0, Warp::Linear, Nodes::Ends);
        Disney {
            params,
            d,
            kc,
            albedo: Table2::from_rows(MU_AXIS, phi, vec![vec![[0.0; 3]; N_MU]; 2]),
            coat_albedo: Table1::from_nodes(MU_AXIS, vec![[0.0]; N_MU]),
        }
    }

    /// The lobes of f(wi, wo) for a unit local `wi` (module docs).
    #[inline(always)]
    pub fn lobes<R: Real>(&self, p: &DisneyPrepared<R>, wi: V3<R>) -> (DisneyLobes<R>, R::Mask) {
        let d = &self.d;
        let h = HalfAngles::new(wi, &p.o);
        let (ci, co) = (h.cos_i, h.cos_o);
        let cos2_d = h.cos_d * h.cos_d;
        let w_i = schlick_weight(ci);
        let w_h = sheen_burley(h.cos_d);

        let l = &p.lanes;
        let rough = l.roughness;
        let fd = fd_burley(rough, cos2_d, w_i, p.w_o);
        let ss = f_subsurface_burley(rough, cos2_d, w_i, p.w_o, ci, co);
        let base = (ss - fd).mul_add(l.subsurface, fd);
        let diffuse = l.diffuse * base + l.sheen * w_h;

        let inv_4 = (R::splat(4.0) * ci * co).rcp();
        let (ax, ay) = (R::splat(d.alpha_x), R::splat(d.alpha_y));
        let s = h.s;
        let d_s = d_ggx_aniso(
            ax,
            ay,
            s.x * s.x * h.inv_len2,
            s.y * s.y * h.inv_len2,
            h.cos2_h,
        );
        let g1_i = g1_smith(lambda_ggx_aniso(ax, ay, wi.x, wi.y, ci));
        let mut specular = f_schlick(l.cspec0, h.cos_d) * (d_s * g1_i * p.g1_o * inv_4);
        if let Some(k) = &self.kc {
            specular += k.f(ci, p.one_minus_e_o);
        }

        let d_r = d_gtr(R::splat(d.clearcoat_alpha), 1.0, h.cos2_h, h.sin2_h);
        let g1_ci = g1_smith(lambda_ggx(R::splat(CLEARCOAT_G_ALPHA), ci));
        let f_r = R::splat(1.0 - CLEARCOAT_F0).mul_add(w_h, R::splat(CLEARCOAT_F0));
        let clearcoat = R::splat(d.clearcoat_weight) * f_r * d_r * g1_ci * p.g1_coat_o * inv_4;
        (
            DisneyLobes {
                diffuse,
                specular,
                clearcoat,
            },
            h.above,
        )
    }
}

impl Brdf for Disney {
    type Params<R: Real> = DisneyLaneParams<R>;
    type Pixel<R: Real> = DisneyLaneParams<R>;
    type Prepared<R: Real> = DisneyPrepared<R>;
    type PolygonPrepared<R: Real> = DisneyPolygons<R>;

    const ANISOTROPIC: bool = true;
    const POLYGON_LIGHTS: bool = true;

    #[inline(always)]
    fn params<R: Real>(&self) -> DisneyLaneParams<R> {
        let d = &self.d;
        DisneyLaneParams {
            diffuse: rgb(d.diffuse),
            sheen: rgb(d.sheen),
            cspec0: rgb(d.cspec0),
            roughness: R::splat(d.roughness),
            subsurface: R::splat(d.subsurface),
        }
    }

    /// The parameters themselves: nothing to derive before the view.
    #[inline(always)]
    fn pixel<R: Real>(&self, params: &DisneyLaneParams<R>) -> DisneyLaneParams<R> {
        *params
    }

    #[inline(always)]
    fn params_lane<R: Real>(p: &DisneyLaneParams<R>, i: usize) -> DisneyLaneParams<f64> {
        DisneyLaneParams {
            diffuse: p.diffuse.lane(i),
            sheen: p.sheen.lane(i),
            cspec0: p.cspec0.lane(i),
            roughness: p.roughness.lane(i),
            subsurface: p.subsurface.lane(i),
        }
    }

    #[inline(always)]
    fn prepare_with<R: Real>(&self, params: &DisneyLaneParams<R>, wo: V3<R>) -> DisneyPrepared<R> {
        let o = Outgoing::new(wo);
        let (ax, ay) = (R::splat(self.d.alpha_x), R::splat(self.d.alpha_y));
        DisneyPrepared {
            w_o: schlick_weight(o.cos_o),
            g1_o: g1_smith(lambda_ggx_aniso(ax, ay, wo.x, wo.y, o.cos_o)),
            g1_coat_o: g1_smith(lambda_ggx(R::splat(CLEARCOAT_G_ALPHA), o.cos_o)),
            one_minus_e_o: match &self.kc {
                Some(k) => k.prepare(o.cos_o),
                None => R::ZERO,
            },
            o,
            lanes: *params,
        }
    }

    /// The two LTC lookups (specular; clearcoat when present), the
    /// lobes' albedos under Schlick's split, and the diffuse albedo, each
    /// zero where the view is below the horizon.
    #[inline(always)]
    fn prepare_polygons<R: Real>(&self, p: &DisneyPrepared<R>) -> DisneyPolygons<R> {
        let (d, o) = (&self.d, &p.o);
        // A material constant: the branch is the same in every lane.
        let spec = if d.alpha_x != d.alpha_y && d.alpha_x.max(d.alpha_y) <= 1.0 {
            self.anisotropic_ltc(o.wo)
        } else {
            let l = LtcGgx::new(R::splat(d.spec_ltc_alpha), o.wo);
            // An anisotropic lobe beyond α = 1 goes through the isotropic
            // fit uncorrected: the correction follows an isotropic lobe.
            if d.alpha_x == d.alpha_y {
                l.with_separable_smith()
            } else {
                l.without_lobe()
            }
        };
        let c = p.lanes.cspec0;
        let specular = Rgb::new(
            spec.schlick_albedo(c.x),
            spec.schlick_albedo(c.y),
            spec.schlick_albedo(c.z),
        );
        // A material constant: the branch is the same in every lane.
        let coat = (d.clearcoat_weight > 0.0).then(|| {
            let mut c = LtcCoat::new(R::splat(d.coat_ln_alpha), o.wo);
            let k = R::select(o.above, R::splat(d.clearcoat_weight), R::ZERO);
            c.scale = c.scale.map(|s| k * s);
            c
        });
        let mut diffuse = diffuse_albedo_of(&p.lanes, o.cos_o.min(R::ONE));
        if let Some(k) = &self.kc {
            diffuse += Rgb::from_f32(k.factor) * p.one_minus_e_o;
        }
        DisneyPolygons {
            spec,
            coat,
            specular: Rgb::select(o.above, specular, Rgb::zero()),
            diffuse: Rgb::select(o.above, diffuse, Rgb::zero()),
        }
    }

    /// Specular through its GGX LTC, clearcoat through its two fitted LTCs,
    /// the diffuse lobes as their albedo at μo times the form factor
    /// (module docs, "Polygon lights").
    #[inline(always)]
    fn polygon_local_with<R: Real>(
        &self,
        _p: &DisneyPrepared<R>,
        pp: &DisneyPolygons<R>,
        poly: &PolygonLocal<R>,
    ) -> Rgb<R> {
        let (ff, spec) = pp.spec.form_factor_and_integral(poly);
        let mut e = pp.specular * spec + pp.diffuse * ff;
        if let Some(coat) = &pp.coat {
            e += Rgb::splat(coat.integral(poly));
        }
        e
    }

    #[inline(always)]
    fn f_local<R: Real>(&self, p: &DisneyPrepared<R>, wi: V3<R>) -> Rgb<R> {
        let (l, above) = self.lobes(p, wi);
        let f = l.diffuse + l.specular + Rgb::splat(l.clearcoat);
        Rgb::select(above, f, Rgb::zero())
    }

    #[inline(always)]
    fn albedo_local<R: Real>(&self, p: &DisneyPrepared<R>) -> Rgb<R> {
        let wo = p.o.wo;
        let xy2 = wo.x.mul_add(wo.x, wo.y * wo.y);
        // At normal incidence φo is moot: the floor only keeps 0/0 away.
        let c2 = wo.x * wo.x / xy2.max(R::splat(1e-30));
        let [r, g, b] = self.albedo.lookup(wo.z, c2);
        Rgb::select(p.o.above, Rgb::new(r, g, b), Rgb::zero())
    }

    /// The diffuse lobes' albedo (diffuse, subsurface blend, sheen) and
    /// the compensation lobe's on the irradiance, as for polygon lights;
    /// the clearcoat's (from its own μo table) on the GGX lobe equivalent
    /// to its GTR1 about the normal; the rest of ρ(wo), the specular
    /// lobe's, on the GGX lobe at √(αx αy).
    #[inline(always)]
    fn env_lobes<R: Real>(&self, p: &DisneyPrepared<R>) -> EnvLobes<R> {
        let (o, above) = (&p.o, p.o.above);
        let total = self.albedo_local(p);
        let mut diffuse = diffuse_albedo_of(&p.lanes, o.cos_o.min(R::ONE));
        if let Some(k) = &self.kc {
            diffuse += Rgb::from_f32(k.factor) * p.one_minus_e_o;
        }
        let diffuse = Rgb::select(above, diffuse, Rgb::zero());
        // A material constant: the branch is the same in every lane.
        if self.d.clearcoat_weight <= 0.0 {
            return EnvLobes::split(total, diffuse, R::splat(self.d.env_roughness));
        }
        let [coat] = self.coat_albedo.lookup(o.wo.z.max(R::ZERO));
        let coat = R::select(above, coat.max(R::ZERO), R::ZERO);
        let under = total - Rgb::splat(coat);
        let under = Rgb::new(
            under.x.max(R::ZERO),
            under.y.max(R::ZERO),
            under.z.max(R::ZERO),
        );
        EnvLobes::split(under, diffuse, R::splat(self.d.env_roughness)).with_coat(
            coat,
            R::splat(self.d.coat_env_roughness),
            V3::new(R::ZERO, R::ZERO, R::ONE),
        )
    }
}
