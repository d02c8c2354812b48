//! A Disney material under polygon lights: its per-pixel state and the
//! anisotropic specular lobe's LTC (see the parent module, "Polygon lights").

use super::*;

#[derive(Clone, Copy)]
pub struct DisneyPolygons<R: Real> {
    /// The specular lobe's GGX LTC (sheared for anisotropic lobes).
    pub spec: LtcGgx<R>,
    /// The clearcoat's fitted cosines (ltc/coat.rs), their scales times
    /// ¼ clearcoat (0 where the view is below the horizon); `None`
    /// without clearcoat (a material constant: nothing to fill per pixel).
    pub coat: Option<LtcCoat<R>>,
    /// C_spec0 (n − n_w) + n_w per channel.
    pub specular: Rgb<R>,
    /// The diffuse lobes' directional albedo at μo (plus the compensation
    /// lobe's factor · (1 − E(μo))): what multiplies the form factor.
    pub(crate) diffuse: Rgb<R>,
}

impl Disney {
    /// The GGX LTC of the anisotropic specular lobe at the view `wo`
    /// (module docs, "Polygon lights"): the isotropic fit at α_ref, its
    /// cosine's xy-plane sheared and scaled by L⁻¹, L = √C / α_ref, C the
    /// 2 × 2 covariance of the half-vector slopes in the view's frame
    /// (x along the view's azimuth, y across it).
    #[inline(always)]
    pub(crate) fn anisotropic_ltc<R: Real>(&self, wo: V3<R>) -> LtcGgx<R> {
        let d = &self.d;
        let (ax2, ay2) = (d.alpha_x * d.alpha_x, d.alpha_y * d.alpha_y);
        let r2 = wo.x.mul_add(wo.x, wo.y * wo.y);
        let ok = r2.gt(R::splat(1e-20));
        let inv_r2 = r2.max(R::splat(1e-20)).rcp();
        // cos²φo and cos φo sin φo of the view's azimuth from the tangent
        // (φo = 0 at the normal, where the LTC's frame is the tangent's:
        // ltc/ggx.rs).
        let c2 = R::select(ok, wo.x * wo.x * inv_r2, R::ONE);
        let cs = R::select(ok, wo.x * wo.y * inv_r2, R::ZERO);
        // C = [[p, κ], [κ, q]]: α² along the view's plane, across it, and
        // their covariance (p + q = αx² + αy², pq − κ² = αx² αy²).
        let p = c2.mul_add(R::splat(ax2 - ay2), R::splat(ay2));
        let q = R::splat(ax2 + ay2) - p;
        let kappa = R::splat(ay2 - ax2) * cs;
        // α_ref² = μo² αx αy + (1 − μo²) p: the isotropic equivalent at
        // the normal (where the lobe must not depend on φo), the α along
        // the view's plane at grazing views.
        let m2 = wo.z * wo.z;
        let a_ref = (R::splat(d.alpha_x * d.alpha_y) * m2)
            .mul_add(R::ONE, p * (R::ONE - m2))
            .sqrt();
        // The stretch below leaves the isotropic lobe: no correction.
        let mut l = LtcGgx::new(a_ref, wo).without_lobe();
        // √C = (C + s I)/t with s = αx αy, t = αx + αy; L⁻¹ = α_ref t /
        // (s t²) · [[q + s, −κ], [−κ, p + s]] (det(C + s I) = s t²).
        let s = R::splat(d.alpha_x * d.alpha_y);
        let f = a_ref * R::splat(1.0 / (d.alpha_x * d.alpha_y * (d.alpha_x + d.alpha_y)));
        let (i11, i12, i22) = ((q + s) * f, -kappa * f, (p + s) * f);
        let (rx, ry) = (l.rx, l.ry);
        l.rx = rx * i11 + ry * i12;
        l.ry = rx * i12 + ry * i22;
        l
    }
}
