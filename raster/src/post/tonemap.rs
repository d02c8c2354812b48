//! The tone curves ([`Tonemap`]) that map linear HDR radiance into
//! [0, 1] per channel, scalar and 8 lanes at once.

use specula_core::{f32x8, Real};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Tonemap {
    /// Clamp each channel to [0, 1].
    #[default]
    Clamp,
    /// x / (1 + x) per channel.   \[Reinhard02\]
    Reinhard,
    /// Narkowicz's fit of the ACES filmic curve.   \[Narkowicz15\]
    Aces,
}

impl Tonemap {
    #[inline]
    pub fn apply(self, x: f32) -> f32 {
        // NaN and negatives become 0, so no NaN reaches the encoder; every
        // curve is within 1e-18 of 1 past 1e18, and capping there keeps x²
        // (ACES) and 1 + x (Reinhard) finite for +inf.
        let x = if x > 0.0 { x.min(1e18) } else { 0.0 };
        match self {
            Tonemap::Clamp => x.min(1.0),
            Tonemap::Reinhard => x / (1.0 + x),
            Tonemap::Aces => {
                ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
            }
        }
    }

    /// [`Tonemap::apply`] on 8 values: the same IEEE operations in the same
    /// order (no fused multiply-adds), so every lane equals the scalar
    /// result bit for bit (a test checks it).
    #[inline(always)]
    pub(crate) fn apply_x8(self, x: f32x8) -> f32x8 {
        let c = |v: f32| f32x8::splat(v);
        let x = Real::select(x.gt(f32x8::ZERO), Real::min(x, c(1e18)), f32x8::ZERO);
        match self {
            Tonemap::Clamp => Real::min(x, c(1.0)),
            Tonemap::Reinhard => x / (c(1.0) + x),
            Tonemap::Aces => {
                let num = x * (c(2.51) * x + c(0.03));
                let den = x * (c(2.43) * x + c(0.59)) + c(0.14);
                Real::clamp(num / den, f32x8::ZERO, c(1.0))
            }
        }
    }
}

/// The tone curve a monomorphized post loop was built for.
pub(super) fn curve_of<const CURVE: u8>() -> Tonemap {
    match CURVE {
        0 => Tonemap::Clamp,
        1 => Tonemap::Reinhard,
        _ => Tonemap::Aces,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tonemaps_send_nan_to_black_and_stay_in_range() {
        for op in [Tonemap::Clamp, Tonemap::Reinhard, Tonemap::Aces] {
            assert_eq!(op.apply(f32::NAN), 0.0);
            for x in [0.0, 0.1, 1.0, 10.0, 1e30, f32::INFINITY] {
                let y = op.apply(x);
                assert!((0.0..=1.0).contains(&y), "{op:?}({x}) = {y}");
            }
        }
    }
}
