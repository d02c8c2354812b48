//! One source, three precisions: the `Real` lane trait.
//!
//! Material terms are written once as `#[inline(always)]` generic functions over
//! `R: Real` and instantiated for
//! - `f32`: the scalar path (`specula render --scalar`),
//! - `f64`: the high-precision reference the tests compare against,
//! - `wide::f32x8`: the hot path, 8 pixels per call.
//!
//! Branches become [`Real::select`]; a lane that a mask removes may hold NaN or
//! inf before the select, never after.

use core::ops::{Add, AddAssign, BitAnd, BitOr, Div, Mul, MulAssign, Neg, Not, Sub, SubAssign};
use wide::f32x8;

/// A per-lane boolean: `bool` for the scalar types, an all-ones/all-zeros lane
/// pattern for the SIMD type.
pub trait Mask: Copy + BitAnd<Output = Self> + BitOr<Output = Self> + Not<Output = Self> {
    /// True if any lane is set.
    fn any(self) -> bool;
    /// True if every lane is set.
    fn all(self) -> bool;
    /// Lane `i` is set (bit `i` of the result).
    fn bits(self) -> u32;
}

impl Mask for bool {
    #[inline(always)]
    fn any(self) -> bool {
        self
    }
    #[inline(always)]
    fn all(self) -> bool {
        self
    }
    #[inline(always)]
    fn bits(self) -> u32 {
        self as u32
    }
}

impl Mask for f32x8 {
    #[inline(always)]
    fn any(self) -> bool {
        f32x8::any(self)
    }
    #[inline(always)]
    fn all(self) -> bool {
        f32x8::all(self)
    }
    #[inline(always)]
    fn bits(self) -> u32 {
        self.to_bitmask()
    }
}

/// Arithmetic on one lane or a packet of lanes; see the module docs.
pub trait Real:
    Copy
    + Send
    + Sync
    + core::fmt::Debug
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
{
    type Mask: Mask;
    /// Number of lanes (1 for the scalar types).
    const LANES: usize;
    const ZERO: Self;
    const ONE: Self;
    const HALF: Self;
    const PI: Self;
    const FRAC_1_PI: Self;

    /// Every lane set to `v` (rounded to the lane precision).
    fn splat(v: f64) -> Self;
    /// Lanes from the first `LANES` values of `s` (f32 storage for all precisions).
    fn load(s: &[f32]) -> Self;
    /// Writes the lanes to the first `LANES` values of `out`.
    fn store(self, out: &mut [f32]);
    /// Lane `i` holds `i` as a number: 0 for the scalar types, 0..7 for f32x8.
    fn lane_index() -> Self;
    /// Lane `i` as f64.
    fn lane(self, i: usize) -> f64;
    /// Mask with lane `i` set iff bit `i` of `bits` is.
    fn mask_from_bits(bits: u32) -> Self::Mask;

    fn sqrt(self) -> Self;
    /// `self * a + b`, fused where the lane type has FMA.
    fn mul_add(self, a: Self, b: Self) -> Self;
    /// The larger value; if `o` is NaN the result is `self`.
    fn max(self, o: Self) -> Self;
    /// The smaller value; if `o` is NaN the result is `self`.
    fn min(self, o: Self) -> Self;
    fn abs(self) -> Self;
    fn exp(self) -> Self;
    fn ln(self) -> Self;

    fn lt(self, o: Self) -> Self::Mask;
    fn le(self, o: Self) -> Self::Mask;
    fn gt(self, o: Self) -> Self::Mask;
    fn ge(self, o: Self) -> Self::Mask;
    /// Lanes that are neither NaN nor ±inf.
    fn is_finite(self) -> Self::Mask;
    /// `a` where `m` is set, else `b`.
    fn select(m: Self::Mask, a: Self, b: Self) -> Self;

    /// Clamps to [lo, hi]; NaN lanes become `lo`.
    #[inline(always)]
    fn clamp(self, lo: Self, hi: Self) -> Self {
        lo.max(self).min(hi)
    }
    #[inline(always)]
    fn sqr(self) -> Self {
        self * self
    }
}

macro_rules! scalar_real {
    ($t:ty, $pi:expr, $inv_pi:expr) => {
        impl Real for $t {
            type Mask = bool;
            const LANES: usize = 1;
            const ZERO: Self = 0.0;
            const ONE: Self = 1.0;
            const HALF: Self = 0.5;
            const PI: Self = $pi;
            const FRAC_1_PI: Self = $inv_pi;

            #[inline(always)]
            fn splat(v: f64) -> Self {
                v as $t
            }
            #[inline(always)]
            fn load(s: &[f32]) -> Self {
                s[0] as $t
            }
            #[inline(always)]
            fn store(self, out: &mut [f32]) {
                out[0] = self as f32;
            }
            #[inline(always)]
            fn lane_index() -> Self {
                0.0
            }
            #[inline(always)]
            fn lane(self, _i: usize) -> f64 {
                self as f64
            }
            #[inline(always)]
            fn mask_from_bits(bits: u32) -> bool {
                bits & 1 != 0
            }
            #[inline(always)]
            fn sqrt(self) -> Self {
                <$t>::sqrt(self)
            }
            #[inline(always)]
            fn mul_add(self, a: Self, b: Self) -> Self {
                <$t>::mul_add(self, a, b)
            }
            #[inline(always)]
            fn max(self, o: Self) -> Self {
                <$t>::max(self, o)
            }
            #[inline(always)]
            fn min(self, o: Self) -> Self {
                <$t>::min(self, o)
            }
            #[inline(always)]
            fn abs(self) -> Self {
                <$t>::abs(self)
            }
            #[inline(always)]
            fn exp(self) -> Self {
                <$t>::exp(self)
            }
            #[inline(always)]
            fn ln(self) -> Self {
                <$t>::ln(self)
            }
            #[inline(always)]
            fn lt(self, o: Self) -> bool {
                self < o
            }
            #[inline(always)]
            fn le(self, o: Self) -> bool {
                self <= o
            }
            #[inline(always)]
            fn gt(self, o: Self) -> bool {
                self > o
            }
            #[inline(always)]
            fn ge(self, o: Self) -> bool {
                self >= o
            }
            #[inline(always)]
            fn is_finite(self) -> bool {
                <$t>::is_finite(self)
            }
            #[inline(always)]
            fn select(m: bool, a: Self, b: Self) -> Self {
                if m {
                    a
                } else {
                    b
                }
            }
        }
    };
}

scalar_real!(f32, core::f32::consts::PI, core::f32::consts::FRAC_1_PI);
scalar_real!(f64, core::f64::consts::PI, core::f64::consts::FRAC_1_PI);

impl Real for f32x8 {
    type Mask = f32x8;
    const LANES: usize = 8;
    const ZERO: Self = f32x8::splat(0.0);
    const ONE: Self = f32x8::splat(1.0);
    const HALF: Self = f32x8::splat(0.5);
    const PI: Self = f32x8::splat(core::f32::consts::PI);
    const FRAC_1_PI: Self = f32x8::splat(core::f32::consts::FRAC_1_PI);

    #[inline(always)]
    fn splat(v: f64) -> Self {
        f32x8::splat(v as f32)
    }
    #[inline(always)]
    fn load(s: &[f32]) -> Self {
        let a: [f32; 8] = s[..8].try_into().expect("slice of 8");
        f32x8::new(a)
    }
    #[inline(always)]
    fn store(self, out: &mut [f32]) {
        out[..8].copy_from_slice(self.as_array());
    }
    #[inline(always)]
    fn lane_index() -> Self {
        f32x8::new([0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0])
    }
    #[inline(always)]
    fn lane(self, i: usize) -> f64 {
        self.as_array()[i] as f64
    }
    #[inline(always)]
    fn mask_from_bits(bits: u32) -> Self {
        let lanes = f32x8::new(core::array::from_fn(|i| ((bits >> i) & 1) as f32));
        lanes.simd_ne(f32x8::ZERO)
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f32x8::sqrt(self)
    }
    #[inline(always)]
    fn mul_add(self, a: Self, b: Self) -> Self {
        f32x8::mul_add(self, a, b)
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        f32x8::max(self, o)
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        f32x8::min(self, o)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f32x8::abs(self)
    }
    #[inline(always)]
    fn exp(self) -> Self {
        f32x8::exp(self)
    }
    #[inline(always)]
    fn ln(self) -> Self {
        f32x8::ln(self)
    }
    #[inline(always)]
    fn lt(self, o: Self) -> Self {
        self.simd_lt(o)
    }
    #[inline(always)]
    fn le(self, o: Self) -> Self {
        self.simd_le(o)
    }
    #[inline(always)]
    fn gt(self, o: Self) -> Self {
        self.simd_gt(o)
    }
    #[inline(always)]
    fn ge(self, o: Self) -> Self {
        self.simd_ge(o)
    }
    #[inline(always)]
    fn is_finite(self) -> Self {
        f32x8::is_finite(self)
    }
    #[inline(always)]
    fn select(m: Self, a: Self, b: Self) -> Self {
        m.select(a, b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lanes(v: f32x8) -> [f32; 8] {
        v.to_array()
    }

    #[test]
    fn select_and_compare_agree_lane_by_lane() {
        let a = [0.5f32, -1.0, 2.0, f32::NAN, f32::INFINITY, 0.0, -0.0, 3.0];
        let b = [1.0f32, -2.0, 2.0, 1.0, 1.0, 0.0, 1.0, f32::NAN];
        let va = f32x8::load(&a);
        let vb = f32x8::load(&b);
        let sel = lanes(f32x8::select(va.lt(vb), va, vb));
        let mx = lanes(va.max(vb));
        let fin = va.is_finite().bits();
        for i in 0..8 {
            let s = f32::select(a[i].lt(b[i]), a[i], b[i]);
            assert_eq!(s.to_bits(), sel[i].to_bits(), "select lane {i}");
            let m = a[i].max(b[i]);
            assert!(
                m == mx[i] || (m.is_nan() && mx[i].is_nan()),
                "max lane {i}: {m} vs {}",
                mx[i]
            );
            assert_eq!(a[i].is_finite(), fin & (1 << i) != 0, "is_finite lane {i}");
        }
    }

    #[test]
    fn exp_and_ln_match_f64_to_f32_precision() {
        let xs = [-20.0f32, -3.5, -1.0, -0.1, 0.0, 0.3, 2.0, 10.0];
        let e = lanes(f32x8::load(&xs).exp());
        for (x, got) in xs.iter().zip(e) {
            let want = (*x as f64).exp();
            assert!(
                ((got as f64 - want) / want).abs() < 1e-6,
                "exp({x}) = {got}, want {want}"
            );
        }
        let ys = [1e-6f32, 0.01, 0.5, 1.0, 1.5, 10.0, 1e3, 1e20];
        let l = lanes(f32x8::load(&ys).ln());
        for (y, got) in ys.iter().zip(l) {
            let want = (*y as f64).ln();
            assert!(
                (got as f64 - want).abs() < 2e-6 * want.abs().max(1.0),
                "ln({y}) = {got}, want {want}"
            );
        }
    }
}
