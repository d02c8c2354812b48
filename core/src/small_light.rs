//! How a GGX LTC table does per pixel under a small light, measured against
//! the reference quadrature (ltc/reference.rs): what core/tests/ltc_ggx.rs
//! bounds and what `specula fit-ltc --check` prints. The table is read as
//! the runtime reads the committed one ([`Lookup`]: splined along the
//! view, with the lobe's correction).
//!
//! **The light**: a one-sided 0.3 × 0.3 square (about 0.08 sr seen from
//! distance 1) facing down.
//!
//! **The scenes** (GGX, height-correlated Smith, F = 1):
//! - a sphere of radius 1 at the origin under the light at height 2 (1
//!   above its top), seen by an orthographic camera looking down at 31°
//!   (`SPHERE_VIEW`): a grid of pixels over its disc;
//! - a floor z = 0 under the light at height 1, seen from a point camera at
//!   (0, −2, 1): a grid of points over x ∈ [−1, 1], y ∈ [−1.8, 1.2] (the
//!   highlight is at y = −1, views about 10–75°).
//!
//! A pixel counts when its reference is at least [`LIT`] of the scene's
//! brightest: its error is |LTC / reference − 1|.
//!
//! **The view sweep**: the light at distance 1 in the mirror direction of a
//! view in the xz-plane, facing the shading point, and the ratio
//! LTC / reference as the view runs over the table's view axis
//! y = √(1 − μo). Its second
//! difference with step h = half a row is taken centred on each row node
//! (the stencil straddles the node: a kink there shows) and centred on each
//! row's midpoint (the stencil stays inside the row).

use crate::light::{PolygonLocal, MAX_POLYGON_VERTICES};
use crate::ltc::ggx::{Lookup, LtcGgx, Y_AXIS};
use crate::ltc::reference::{integrate_polygon, Tolerance};
use crate::models::microfacet::{Fresnel, Microfacet, MicrofacetParams, Ndf, Smith};
use crate::table::Table2;
use crate::vec3::V3;
use crate::Brdf;

/// Pixels whose reference is below this fraction of the scene's brightest
/// are not counted.
pub const LIT: f64 = 0.1;
/// The sphere's camera: the direction toward it (unit).
pub(crate) const SPHERE_VIEW: [f64; 3] = [0.0, -0.857_492_925_712_544_3, 0.514_495_755_427_526_5];
/// Side of the light.
pub(crate) const SIDE: f64 = 0.3;

/// One of the two scenes of the module docs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scene {
    Sphere,
    Floor,
}

/// A scene's per-pixel error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelError {
    /// Mean and largest |LTC / reference − 1| over the counted pixels.
    pub mean: f64,
    pub worst: f64,
    /// Σ |LTC − reference| / Σ reference over the counted pixels.
    pub weighted: f64,
    pub pixels: usize,
    /// The worst pixel: view angle θo and the light centre's polar angle
    /// θl and azimuth from the view's φl (degrees), LTC and reference.
    pub worst_at: [f64; 5],
}

/// The second differences of the view sweep's ratio (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Kinks {
    /// Centred on row nodes, and on row midpoints.
    pub across: Vec<f64>,
    pub within: Vec<f64>,
}

impl Kinks {
    fn rms(v: &[f64]) -> f64 {
        (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt()
    }
    /// Root mean square of the second differences across rows.
    pub fn across_rms(&self) -> f64 {
        Kinks::rms(&self.across)
    }
    /// Root mean square of the second differences within rows.
    pub fn within_rms(&self) -> f64 {
        Kinks::rms(&self.within)
    }
}

/// The GGX lobe with F = 1 at roughness `alpha`.
pub(crate) fn lobe(alpha: f64) -> Microfacet {
    Microfacet::new_without_table(
        MicrofacetParams {
            ndf: Ndf::Ggx,
            alpha: alpha as f32,
            smith: Smith::HeightCorrelated,
            fresnel: Fresnel::Schlick { f0: [1.0; 3] },
            diffuse: [0.0; 3],
            gtr_lambda: Default::default(),
        },
        None,
    )
}

/// A shading point: position, unit normal, unit direction to the viewer.
type Pixel = (V3<f64>, V3<f64>, V3<f64>);

/// The light's corners, counter-clockwise seen from below (front down).
fn light(height: f64) -> [V3<f64>; 4] {
    let h = SIDE / 2.0;
    [
        V3::new(-h, -h, height),
        V3::new(-h, h, height),
        V3::new(h, h, height),
        V3::new(h, -h, height),
    ]
}

/// The scene's pixels on an `n` × `n` grid and its light.
pub(crate) fn pixels(scene: Scene, n: usize) -> (Vec<Pixel>, [V3<f64>; 4]) {
    let t = |k: usize| (k as f64 + 0.5) / n as f64;
    match scene {
        Scene::Sphere => {
            let c = V3::new(SPHERE_VIEW[0], SPHERE_VIEW[1], SPHERE_VIEW[2]);
            let e1 = V3::new(1.0, 0.0, 0.0);
            let e2 = c.cross(e1);
            let mut px = Vec::new();
            for a in 0..n {
                for b in 0..n {
                    let (u, v) = (2.0 * t(a) - 1.0, 2.0 * t(b) - 1.0);
                    let r2 = u * u + v * v;
                    if r2 < 1.0 {
                        let p = e1 * u + e2 * v + c * (1.0 - r2).sqrt();
                        px.push((p, p, c));
                    }
                }
            }
            (px, light(2.0))
        }
        Scene::Floor => {
            let eye = V3::new(0.0, -2.0, 1.0);
            let mut px = Vec::new();
            for a in 0..n {
                for b in 0..n {
                    let p = V3::new(-1.0 + 2.0 * t(a), -1.8 + 3.0 * t(b), 0.0);
                    px.push((p, V3::new(0.0, 0.0, 1.0), (eye - p).normalize()));
                }
            }
            (px, light(1.0))
        }
    }
}

/// An orthonormal frame (t, b) around the unit normal `n`.
fn frame(n: V3<f64>) -> (V3<f64>, V3<f64>) {
    let a = if n.x.abs() < 0.9 {
        V3::new(1.0, 0.0, 0.0)
    } else {
        V3::new(0.0, 1.0, 0.0)
    };
    let t = a.cross(n).normalize();
    (t, n.cross(t))
}

/// `table`'s LTC value of the lobe (F = 1: n ∫ D, corrected as the
/// runtime does: ltc/ggx.rs) at roughness `alpha`, unit local view `wo`,
/// over the local polygon `q` (one-sided).
pub(crate) fn ltc_value(table: &Lookup, alpha: f64, wo: V3<f64>, q: &[V3<f64>]) -> f64 {
    let y = (1.0 - wo.z.clamp(0.0, 1.0)).sqrt();
    let l = LtcGgx::from_table(table, alpha, alpha.sqrt(), y, wo);
    let mut poly = PolygonLocal {
        vertices: [V3::zero(); MAX_POLYGON_VERTICES],
        len: q.len(),
        two_sided: false,
    };
    poly.vertices[..q.len()].copy_from_slice(q);
    l.n * l.integral(&poly)
}

/// The reference value of the lobe over the local polygon `q`.
pub(crate) fn reference_value(m: &Microfacet, wo: V3<f64>, q: &[V3<f64>]) -> f64 {
    let p = m.prepare(wo);
    let f = |wi: V3<f64>| {
        let c = m.f_cos_local(&p, wi);
        [c.x, c.y, c.z]
    };
    let tol = Tolerance {
        relative: 1e-4,
        absolute: 1e-9,
        max_nodes: 50_000,
    };
    integrate_polygon(q, false, &f, tol).value[0]
}

/// The scene's per-pixel error of `table` (read as the runtime reads the
/// committed one: [`Lookup`]) at roughness `alpha` on an
/// `n` × `n` grid, over the pixels at least `lit` of the brightest.
pub fn pixel_error(table: &Table2<6>, alpha: f64, scene: Scene, n: usize, lit: f64) -> PixelError {
    let table = &Lookup::new(table);
    let m = lobe(alpha);
    let (px, corners) = pixels(scene, n);
    let values: Vec<(f64, f64, [f64; 3])> = px
        .iter()
        .map(|&(p, nrm, view)| {
            let (t, b) = frame(nrm);
            let local = |v: V3<f64>| V3::new(v.dot(t), v.dot(b), v.dot(nrm));
            let q: Vec<V3<f64>> = corners.iter().map(|&c| local(c - p)).collect();
            let wo = local(view);
            if wo.z <= 0.0 {
                return (0.0, 0.0, [0.0; 3]);
            }
            let c = (q[0] + q[1] + q[2] + q[3]).normalize();
            let deg = f64::to_degrees;
            let where_ = [
                deg(wo.z.acos()),
                deg(c.z.acos()),
                deg((c.y.atan2(c.x) - wo.y.atan2(wo.x)).rem_euclid(std::f64::consts::TAU)),
            ];
            (
                ltc_value(table, alpha, wo, &q),
                reference_value(&m, wo, &q),
                where_,
            )
        })
        .collect();
    let top = values.iter().fold(0.0f64, |a, v| a.max(v.1));
    let lit: Vec<(f64, f64, [f64; 3])> = values
        .into_iter()
        .filter(|v| v.1 >= lit * top && v.1 > 0.0)
        .collect();
    let rel = |v: &(f64, f64, [f64; 3])| (v.0 / v.1 - 1.0).abs();
    let w = lit
        .iter()
        .max_by(|a, b| rel(a).total_cmp(&rel(b)))
        .map_or([0.0; 5], |v| [v.2[0], v.2[1], v.2[2], v.0, v.1]);
    PixelError {
        mean: lit.iter().map(rel).sum::<f64>() / lit.len().max(1) as f64,
        worst: lit.iter().map(rel).fold(0.0, f64::max),
        weighted: lit.iter().map(|v| (v.0 - v.1).abs()).sum::<f64>()
            / lit.iter().map(|v| v.1).sum::<f64>().max(1e-300),
        pixels: lit.len(),
        worst_at: w,
    }
}

/// LTC / reference at roughness `alpha` and table view coordinate
/// y = √(1 − μo), the light in the mirror direction (module docs).
pub(crate) fn sweep_ratio(table: &Lookup, m: &Microfacet, alpha: f64, y: f64) -> f64 {
    let mu = 1.0 - y * y;
    let s = (1.0 - mu * mu).max(0.0).sqrt();
    let wo = V3::new(s, 0.0, mu);
    let dir = V3::new(-s, 0.0, mu);
    // The square facing the origin: its sides along y and along dir × y.
    let e1 = V3::new(0.0, 1.0, 0.0) * (SIDE / 2.0);
    let e2 = dir.cross(V3::new(0.0, 1.0, 0.0)) * (SIDE / 2.0);
    let q = [dir - e1 - e2, dir + e1 - e2, dir + e1 + e2, dir - e1 + e2];
    // Counter-clockwise seen from the origin.
    let q: Vec<V3<f64>> = if crate::ltc::reference::newell_normal(&q).dot(dir) < 0.0 {
        q.to_vec()
    } else {
        q.iter().rev().copied().collect()
    };
    ltc_value(table, alpha, wo, &q) / reference_value(m, wo, &q)
}

/// The view sweep's second differences at roughness `alpha` over the rows
/// whose nodes lie in [`y_lo`, `y_hi`] (module docs), `table` read as the
/// runtime reads the committed one.
pub fn kinks(table: &Table2<6>, alpha: f64, y_lo: f64, y_hi: f64) -> Kinks {
    let table = &Lookup::new(table);
    let m = lobe(alpha);
    let dy = 1.0 / (Y_AXIS.n() - 1) as f64;
    let h = dy / 2.0;
    let mut across = Vec::new();
    let mut within = Vec::new();
    for j in 1..Y_AXIS.n() - 1 {
        let y = Y_AXIS.node(j);
        if y < y_lo || y > y_hi {
            continue;
        }
        let r: Vec<f64> = (0..4)
            .map(|k| sweep_ratio(table, &m, alpha, y - h + k as f64 * h))
            .collect();
        // r at y − h, y, y + h, y + 2h: centred on the node, then on the
        // midpoint y + h of the row [y, y + dy].
        across.push(r[0] - 2.0 * r[1] + r[2]);
        within.push(r[1] - 2.0 * r[2] + r[3]);
    }
    Kinks { across, within }
}
