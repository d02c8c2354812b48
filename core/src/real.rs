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

/// A number known only at run time that lanes broadcast often (a table's
/// bounds and sizes): its f64 value and its rounding to f32, made once
/// when the number is, so that f32 lanes read it as it is stored instead
/// of converting it on every use ([`Real::constant`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Constant {
    exact: f64,
    single: f32,
}

impl Constant {
    pub const fn new(v: f64) -> Constant {
        Constant {
            exact: v,
            single: v as f32,
        }
    }

    /// The f64 value.
    pub const fn get(self) -> f64 {
        self.exact
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
    /// The tests' reference precision (f64): a kernel with a cheaper
    /// approximate form uses its exact form where this is true, so f64
    /// stays the oracle the lanes are measured against (ltc/polygon.rs:
    /// the edge integral's θ by atan2 in f64, by a polynomial in f32 and
    /// f32x8, which agree with each other bit for bit).
    const EXACT: bool;

    /// Every lane set to `v` (rounded to the lane precision).
    fn splat(v: f64) -> Self;
    /// `splat(c.get())`, without rounding on each use.
    fn constant(c: Constant) -> Self;
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
    /// 1/√x for finite x > 0 (other inputs give NaN or inf: callers mask or
    /// clamp them): `1 / sqrt(x)`, each step correctly rounded, so every
    /// CPU gives the same bits. (Not the `rsqrtps` estimate refined by a
    /// Newton step: that estimate is not specified to the bit, so the same
    /// binary rendered different pixels on Intel and AMD processors.)
    fn rsqrt(self) -> Self;
    /// 1/x, correctly rounded (a division, for the reason given at
    /// [`Real::rsqrt`]). (Not named `recip`: wide's inherent
    /// `f32x8::recip` is the bare 12-bit `rcpps` estimate and would
    /// silently win method lookup.)
    fn rcp(self) -> Self;
    /// `self * a + b`, fused where the lane type has FMA.
    fn mul_add(self, a: Self, b: Self) -> Self;
    /// `self` if `self > o`, else `o`, on every target: a NaN `self` gives
    /// `o` (so `x.max(ZERO)` clears NaN) and a NaN `o` gives NaN. A select
    /// on the comparison, or on x86 `maxps`, whose definition is that rule
    /// (not the platform's generic max: NEON `fmax` propagates NaN).
    fn max(self, o: Self) -> Self;
    /// `self` if `self < o`, else `o`; NaN as [`Real::max`].
    fn min(self, o: Self) -> Self;
    fn abs(self) -> Self;
    /// Largest integer ≤ self.
    fn floor(self) -> Self;
    fn exp(self) -> Self;
    fn ln(self) -> Self;
    /// eˣ − 1, accurate for small x.
    fn exp_m1(self) -> Self;
    /// ln(1 + x), accurate for small x.
    fn ln_1p(self) -> Self;
    /// The angle of the point (x, y) = (`x`, `self`) in [−π, π], as
    /// `f64::atan2`; accurate where acos and asin are not (near ±1).
    /// f32x8: wide's polynomial (Cephes), within 2 ulp of f32 (tested).
    fn atan2(self, x: Self) -> Self;

    fn lt(self, o: Self) -> Self::Mask;
    fn le(self, o: Self) -> Self::Mask;
    fn gt(self, o: Self) -> Self::Mask;
    fn ge(self, o: Self) -> Self::Mask;
    /// Lanes that are neither NaN nor ±inf.
    fn is_finite(self) -> Self::Mask;
    /// `a` where `m` is set, else `b`.
    fn select(m: Self::Mask, a: Self, b: Self) -> Self;
    /// Per lane, `table[index]` as a lane value: the one memory read of
    /// table lookups (table.rs). Index lanes hold integral values in
    /// `0..table.len()` (exact in f32 up to 2²⁴). Outside that, never a
    /// read out of bounds: on the scalar types an index past the end
    /// panics and a negative or NaN one reads `table[0]` (the cast to
    /// usize saturates); f32x8 clamps each lane into range.
    fn gather(table: &[f32], index: Self) -> Self;
    /// Per lane, the 2 × 2 block of RGB texels at `index`, `index + 1`,
    /// `index + stride` and `index + stride + 1` of a table of texels of
    /// three floats each (rows of `stride` texels), as
    /// `[row][column][channel]` lane values: a bilinear lookup's
    /// footprint, every channel read at once. The table holds one float
    /// more after its last texel (f32x8 reads 16 bytes a texel). Index
    /// lanes hold integral values from 0 to the last block's,
    /// `(table.len() - 1) / 3 - stride - 2`; outside that, the scalar
    /// types read as [`Real::gather`] does and f32x8 clamps.
    #[inline(always)]
    fn gather_rgb_block(table: &[f32], index: Self, stride: usize) -> [[[Self; 3]; 2]; 2] {
        let at = |offset: usize| {
            let base = (index + Self::splat(offset as f64)) * Self::splat(3.0);
            core::array::from_fn(|c| Self::gather(table, base + Self::splat(c as f64)))
        };
        [[at(0), at(1)], [at(stride), at(stride + 1)]]
    }

    /// Per lane, the run of `N` consecutive floats of `table` from
    /// `index`: `out[c]` is [`Real::gather`] of `index + c`, each read
    /// clamped as that one clamps. f32x8 reads a lane's run with one load
    /// where every lane's index is integral and its 8 floats lie in the
    /// table (for `N` ≤ 8), transposing the runs in registers, and gathers
    /// otherwise; the values are the same either way.
    #[inline(always)]
    fn gather_run<const N: usize>(table: &[f32], index: Self) -> [Self; N] {
        core::array::from_fn(|c| Self::gather(table, index + Self::splat(c as f64)))
    }

    /// Clamps to [lo, hi] (for lo ≤ hi) as `self.max(lo).min(hi)`: a NaN
    /// `self` becomes `lo`.
    #[inline(always)]
    fn clamp(self, lo: Self, hi: Self) -> Self {
        self.max(lo).min(hi)
    }
    #[inline(always)]
    fn sqr(self) -> Self {
        self * self
    }
}

macro_rules! scalar_real {
    ($t:ty, $exact:expr, $pi:expr, $inv_pi:expr, $rsqrt:expr, $recip:expr, $constant:expr) => {
        impl Real for $t {
            type Mask = bool;
            const LANES: usize = 1;
            const EXACT: bool = $exact;
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
            fn constant(c: Constant) -> Self {
                $constant(c)
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
            fn rsqrt(self) -> Self {
                $rsqrt(self)
            }
            #[inline(always)]
            fn rcp(self) -> Self {
                $recip(self)
            }
            #[inline(always)]
            fn mul_add(self, a: Self, b: Self) -> Self {
                <$t>::mul_add(self, a, b)
            }
            #[inline(always)]
            fn max(self, o: Self) -> Self {
                if self > o {
                    self
                } else {
                    o
                }
            }
            #[inline(always)]
            fn min(self, o: Self) -> Self {
                if self < o {
                    self
                } else {
                    o
                }
            }
            #[inline(always)]
            fn abs(self) -> Self {
                <$t>::abs(self)
            }
            #[inline(always)]
            fn floor(self) -> Self {
                <$t>::floor(self)
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
            fn exp_m1(self) -> Self {
                <$t>::exp_m1(self)
            }
            #[inline(always)]
            fn ln_1p(self) -> Self {
                <$t>::ln_1p(self)
            }
            #[inline(always)]
            fn atan2(self, x: Self) -> Self {
                <$t>::atan2(self, x)
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
            #[inline(always)]
            fn gather(table: &[f32], index: Self) -> Self {
                table[index as usize] as $t
            }
        }
    };
}

scalar_real!(
    f32,
    false,
    core::f32::consts::PI,
    core::f32::consts::FRAC_1_PI,
    |x: f32| 1.0 / x.sqrt(),
    |x: f32| 1.0 / x,
    |c: Constant| c.single
);
scalar_real!(
    f64,
    true,
    core::f64::consts::PI,
    core::f64::consts::FRAC_1_PI,
    |x: f64| 1.0 / x.sqrt(),
    |x: f64| 1.0 / x,
    |c: Constant| c.exact
);

impl Real for f32x8 {
    type Mask = f32x8;
    const LANES: usize = 8;
    const EXACT: bool = false;
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
    fn constant(c: Constant) -> Self {
        f32x8::splat(c.single)
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
        // Lane i keeps bit i of `bits`; equal to that bit alone iff it is set.
        const LANE_BIT: wide::i32x8 = wide::i32x8::new([1, 2, 4, 8, 16, 32, 64, 128]);
        let m = (wide::i32x8::splat(bits as i32) & LANE_BIT).simd_eq(LANE_BIT);
        bytemuck::cast(m)
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f32x8::sqrt(self)
    }
    #[inline(always)]
    fn rsqrt(self) -> Self {
        f32x8::ONE / f32x8::sqrt(self)
    }
    #[inline(always)]
    fn rcp(self) -> Self {
        f32x8::ONE / self
    }
    #[inline(always)]
    fn mul_add(self, a: Self, b: Self) -> Self {
        f32x8::mul_add(self, a, b)
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        max_f32x8(self, o)
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        min_f32x8(self, o)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f32x8::abs(self)
    }
    #[inline(always)]
    fn floor(self) -> Self {
        f32x8::floor(self)
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
    fn exp_m1(self) -> Self {
        f32x8::exp_m1(self)
    }
    #[inline(always)]
    fn ln_1p(self) -> Self {
        f32x8::ln_1p(self)
    }
    #[inline(always)]
    fn atan2(self, x: Self) -> Self {
        f32x8::atan2(self, x)
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
    #[inline(always)]
    fn gather(table: &[f32], index: Self) -> Self {
        // Indices clamped into range (NaN truncates to i32::MIN, then 0):
        // two integer ops that make the read sound whatever the caller did.
        // The bound capped to i32's range (which only lowers it); an empty
        // table stops at `gather_f32x8`'s assert.
        let last = wide::i32x8::splat(table.len().min(i32::MAX as usize) as i32 - 1);
        let i = index.fast_trunc_int().max(wide::i32x8::ZERO).min(last);
        gather_f32x8(table, i)
    }
    #[inline(always)]
    fn gather_run<const N: usize>(table: &[f32], index: Self) -> [Self; N] {
        // The runs are loads where each lane's index is integral (so that
        // index + c is the float index `gather` truncates) and its 8
        // floats are in the table; otherwise `gather`'s clamped reads.
        let i = index.fast_trunc_int();
        let last_start = table.len().min(i32::MAX as usize) as i32 - 8;
        let integral = i.round_float().simd_eq(index).to_bitmask();
        let outside = i.simd_lt(wide::i32x8::ZERO) | i.simd_gt(wide::i32x8::splat(last_start));
        if N <= 8 && last_start >= 0 && integral == 0xFF && outside.to_bitmask() == 0 {
            let runs = gather_runs_f32x8(table, i);
            return core::array::from_fn(|c| runs[c]);
        }
        core::array::from_fn(|c| <Self as Real>::gather(table, index + f32x8::splat(c as f32)))
    }
    #[inline(always)]
    fn gather_rgb_block(table: &[f32], index: Self, stride: usize) -> [[[Self; 3]; 2]; 2] {
        // Clamped as `gather`, to the last block, the bound capped to
        // i32's range; a table too small for one block stops at
        // `gather_rgb_block_f32x8`'s assert.
        let texels = table.len().saturating_sub(1) / 3;
        let last = texels.saturating_sub(stride.saturating_add(2));
        let last = wide::i32x8::splat(last.min(i32::MAX as usize) as i32);
        let i = index.fast_trunc_int().max(wide::i32x8::ZERO).min(last);
        gather_rgb_block_f32x8(table, i, stride)
    }
}

/// `if a > b { a } else { b }` per lane. `vmaxps a, b` is defined as
/// exactly that (Intel SDM: the second operand when either is NaN or both
/// are zero), one instruction where the select below compiles to a compare
/// and a blend (checked in the disassembly); other targets use the select,
/// since e.g. NEON `fmax` propagates NaN. Tested bit for bit against the
/// scalar rule in core/tests/numerics.rs.
#[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
#[inline(always)]
fn max_f32x8(a: f32x8, b: f32x8) -> f32x8 {
    use core::arch::x86_64::_mm256_max_ps;
    // SAFETY: AVX is enabled (cfg).
    bytemuck::cast(unsafe { _mm256_max_ps(bytemuck::cast(a), bytemuck::cast(b)) })
}

/// `if a < b { a } else { b }` per lane; `vminps a, b` as [`max_f32x8`].
#[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
#[inline(always)]
fn min_f32x8(a: f32x8, b: f32x8) -> f32x8 {
    use core::arch::x86_64::_mm256_min_ps;
    // SAFETY: AVX is enabled (cfg).
    bytemuck::cast(unsafe { _mm256_min_ps(bytemuck::cast(a), bytemuck::cast(b)) })
}

#[cfg(not(all(target_arch = "x86_64", target_feature = "avx")))]
#[inline(always)]
fn max_f32x8(a: f32x8, b: f32x8) -> f32x8 {
    a.simd_gt(b).select(a, b)
}

#[cfg(not(all(target_arch = "x86_64", target_feature = "avx")))]
#[inline(always)]
fn min_f32x8(a: f32x8, b: f32x8) -> f32x8 {
    a.simd_lt(b).select(a, b)
}

/// 8 loads at i32 indices already in `0..table.len()`: `vgatherdps`.
/// Measured by `gather_speed` in core/tests/numerics.rs (shared Xeon,
/// AVX2, tables of 64 to 65536 floats): 5.4–11.5 ns per 8 lanes against
/// 7.3–14.3 ns for eight scalar loads, so the hardware gather is kept.
#[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
#[inline(always)]
fn gather_f32x8(table: &[f32], i: wide::i32x8) -> f32x8 {
    use core::arch::x86_64::{__m256i, _mm256_i32gather_ps};
    assert!(!table.is_empty());
    let iv: __m256i = bytemuck::cast(i);
    // SAFETY: AVX2 is enabled (cfg); every index lane is in
    // 0..table.len() (clamped by the caller), so each read is in bounds.
    let v = unsafe { _mm256_i32gather_ps::<4>(table.as_ptr(), iv) };
    bytemuck::cast(v)
}

/// Per-lane fallback of [`gather_f32x8`].
#[cfg(not(all(target_arch = "x86_64", target_feature = "avx2")))]
#[inline(always)]
fn gather_f32x8(table: &[f32], i: wide::i32x8) -> f32x8 {
    let i = i.to_array();
    f32x8::new(core::array::from_fn(|l| table[i[l] as usize]))
}

/// The 2 × 2 RGB texel blocks of 8 lanes at i32 indices already in
/// range ([`Real::gather_rgb_block`]), by loads and transposes instead
/// of gathers: one index per lane moved to a register, four texels read
/// at fixed offsets from it, 16 bytes each (the fourth float, the next
/// texel's or the table's last, unused). A texel of lanes l and l + 4
/// makes one 256-bit row, and a 4 × 4 transpose within each 128-bit half
/// turns four such rows into the channels. When all eight indices are
/// equal, the block's twelve floats are broadcast instead.
#[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
#[inline(always)]
fn gather_rgb_block_f32x8(table: &[f32], i: wide::i32x8, stride: usize) -> [[[f32x8; 3]; 2]; 2] {
    use core::arch::x86_64::{
        __m256, _mm256_set_m128, _mm256_shuffle_ps, _mm256_unpackhi_ps, _mm256_unpacklo_ps,
        _mm_loadu_ps,
    };
    assert!(table.len().saturating_sub(1) / 3 >= stride.saturating_add(2));
    let same = i.simd_eq(wide::i32x8::splat(i.to_array()[0])).to_bitmask() == 0xFF;
    let i = i.to_array();
    // Each lane's block starts at float 3 × index of the top row and of
    // the row below it: one address a lane, the offsets constant.
    let top = table.as_ptr();
    // SAFETY: stride + 2 texels fit in the table (asserted), so the row
    // below starts within it.
    let below = unsafe { top.add(3 * stride) };
    // SAFETY: AVX is enabled (cfg); every index lane is at most
    // (table.len() - 1) / 3 - stride - 2 (clamped by the caller), so the
    // texels at offsets 0, 1, stride and stride + 1 from it start at float
    // 3 (table.len() - 1) / 3 - 3 at the latest, and their 16 bytes (the
    // broadcast path reads the first 12 of them) end within the table;
    // the loads need no alignment.
    unsafe {
        if same {
            // Neighbouring pixels reading a coarse level, mostly.
            let texel = |row: *const f32, offset: usize| -> [f32x8; 3] {
                let at = row.add(3 * i[0] as usize + offset);
                core::array::from_fn(|c| f32x8::splat(*at.add(c)))
            };
            return [
                [texel(top, 0), texel(top, 3)],
                [texel(below, 0), texel(below, 3)],
            ];
        }
        let channels = |row: *const f32, offset: usize| -> [f32x8; 3] {
            let at = |l: usize| _mm_loadu_ps(row.add(3 * i[l] as usize + offset));
            let row = |l: usize| -> __m256 { _mm256_set_m128(at(l + 4), at(l)) };
            // [r0 r1 g0 g1 | r4 r5 g4 g5] and [b0 b1 · · | b4 b5 · ·] of
            // lanes 0, 1 (then 2, 3), then each channel's halves together.
            let (a, b, c, d) = (row(0), row(1), row(2), row(3));
            let (ab_lo, ab_hi) = (_mm256_unpacklo_ps(a, b), _mm256_unpackhi_ps(a, b));
            let (cd_lo, cd_hi) = (_mm256_unpacklo_ps(c, d), _mm256_unpackhi_ps(c, d));
            [
                _mm256_shuffle_ps::<0b01_00_01_00>(ab_lo, cd_lo),
                _mm256_shuffle_ps::<0b11_10_11_10>(ab_lo, cd_lo),
                _mm256_shuffle_ps::<0b01_00_01_00>(ab_hi, cd_hi),
            ]
            .map(bytemuck::cast)
        };
        [
            [channels(top, 0), channels(top, 3)],
            [channels(below, 0), channels(below, 3)],
        ]
    }
}

/// The 8 floats of `table` from each lane's index (every one in
/// `0..=table.len() - 8`, checked by the caller): `out[c]` holds float
/// index + c of each lane. One 32-byte load a lane, then an 8 × 8
/// transpose in registers.
#[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
#[inline(always)]
fn gather_runs_f32x8(table: &[f32], i: wide::i32x8) -> [f32x8; 8] {
    use core::arch::x86_64::{
        _mm256_loadu_ps, _mm256_permute2f128_ps, _mm256_shuffle_ps, _mm256_unpackhi_ps,
        _mm256_unpacklo_ps,
    };
    let i = i.to_array();
    assert!(i.iter().all(|&l| l >= 0 && l as usize + 8 <= table.len()));
    // SAFETY: AVX is enabled (cfg); each lane's 8 floats are in the table
    // (asserted); the loads need no alignment.
    unsafe {
        let r = i.map(|l| _mm256_loadu_ps(table.as_ptr().add(l as usize)));
        // Pairs of lanes interleaved, then quadruples, then the halves.
        let lo = |a: usize| _mm256_unpacklo_ps(r[a], r[a + 1]);
        let hi = |a: usize| _mm256_unpackhi_ps(r[a], r[a + 1]);
        let t = [lo(0), hi(0), lo(2), hi(2), lo(4), hi(4), lo(6), hi(6)];
        let u = [
            _mm256_shuffle_ps::<0b01_00_01_00>(t[0], t[2]),
            _mm256_shuffle_ps::<0b11_10_11_10>(t[0], t[2]),
            _mm256_shuffle_ps::<0b01_00_01_00>(t[1], t[3]),
            _mm256_shuffle_ps::<0b11_10_11_10>(t[1], t[3]),
            _mm256_shuffle_ps::<0b01_00_01_00>(t[4], t[6]),
            _mm256_shuffle_ps::<0b11_10_11_10>(t[4], t[6]),
            _mm256_shuffle_ps::<0b01_00_01_00>(t[5], t[7]),
            _mm256_shuffle_ps::<0b11_10_11_10>(t[5], t[7]),
        ];
        [
            _mm256_permute2f128_ps::<0x20>(u[0], u[4]),
            _mm256_permute2f128_ps::<0x20>(u[1], u[5]),
            _mm256_permute2f128_ps::<0x20>(u[2], u[6]),
            _mm256_permute2f128_ps::<0x20>(u[3], u[7]),
            _mm256_permute2f128_ps::<0x31>(u[0], u[4]),
            _mm256_permute2f128_ps::<0x31>(u[1], u[5]),
            _mm256_permute2f128_ps::<0x31>(u[2], u[6]),
            _mm256_permute2f128_ps::<0x31>(u[3], u[7]),
        ]
        .map(bytemuck::cast)
    }
}

/// Per-lane fallback of [`gather_runs_f32x8`].
#[cfg(not(all(target_arch = "x86_64", target_feature = "avx")))]
#[inline(always)]
fn gather_runs_f32x8(table: &[f32], i: wide::i32x8) -> [f32x8; 8] {
    let i = i.to_array();
    core::array::from_fn(|c| f32x8::new(core::array::from_fn(|l| table[i[l] as usize + c])))
}

/// Per-lane fallback of [`gather_rgb_block_f32x8`].
#[cfg(not(all(target_arch = "x86_64", target_feature = "avx")))]
#[inline(always)]
fn gather_rgb_block_f32x8(table: &[f32], i: wide::i32x8, stride: usize) -> [[[f32x8; 3]; 2]; 2] {
    let i = i.to_array();
    let at = |offset: usize| {
        core::array::from_fn(|c| {
            f32x8::new(core::array::from_fn(|l| {
                table[(i[l] as usize + offset) * 3 + c]
            }))
        })
    };
    [[at(0), at(1)], [at(stride), at(stride + 1)]]
}

/// The per-lane read, for the speed comparison in the tests.
#[doc(hidden)]
#[inline(always)]
pub fn gather_f32x8_per_lane(table: &[f32], index: f32x8) -> f32x8 {
    let last = wide::i32x8::splat(table.len() as i32 - 1);
    let i = index
        .fast_trunc_int()
        .max(wide::i32x8::ZERO)
        .min(last)
        .to_array();
    f32x8::new(core::array::from_fn(|l| table[i[l] as usize]))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lanes(v: f32x8) -> [f32; 8] {
        v.to_array()
    }

    /// A constant's lanes are those of `splat` of its value, bit for bit,
    /// in every precision: rounding once when it is made is rounding on
    /// every use.
    #[test]
    fn a_constant_splats_like_its_value() {
        let values = [
            0.1,
            1.0 / 3.0,
            -2.5e-42,
            1.0e39,
            -0.0,
            f64::INFINITY,
            f64::NAN,
            16_777_217.0,
        ];
        for v in values {
            let c = Constant::new(v);
            assert_eq!(f64::constant(c).to_bits(), f64::splat(v).to_bits(), "{v}");
            assert_eq!(f32::constant(c).to_bits(), f32::splat(v).to_bits(), "{v}");
            let a = <f32x8 as Real>::constant(c).to_array();
            let b = <f32x8 as Real>::splat(v).to_array();
            assert_eq!(a.map(f32::to_bits), b.map(f32::to_bits), "{v}");
            assert_eq!(c.get().to_bits(), v.to_bits());
        }
        // Tables' axes are made in const items: the rounding at compile
        // time is the one at run time.
        const TENTH: Constant = Constant::new(0.1);
        let tenth = std::hint::black_box(0.1f64);
        assert_eq!(f32::constant(TENTH).to_bits(), (tenth as f32).to_bits());
        assert_eq!(f64::constant(TENTH).to_bits(), tenth.to_bits());
    }

    #[test]
    fn select_and_compare_agree_lane_by_lane() {
        let a = [0.5f32, -1.0, 2.0, f32::NAN, f32::INFINITY, 0.0, -0.0, 3.0];
        let b = [1.0f32, -2.0, 2.0, 1.0, 1.0, 0.0, 1.0, f32::NAN];
        let va = f32x8::load(&a);
        let vb = f32x8::load(&b);
        let sel = lanes(f32x8::select(va.lt(vb), va, vb));
        let mx = lanes(Real::max(va, vb));
        let fin = va.is_finite().bits();
        for i in 0..8 {
            let s = f32::select(a[i].lt(b[i]), a[i], b[i]);
            assert_eq!(s.to_bits(), sel[i].to_bits(), "select lane {i}");
            let m = Real::max(a[i], b[i]);
            assert_eq!(
                m.to_bits(),
                mx[i].to_bits(),
                "max lane {i}: {m} vs {}",
                mx[i]
            );
            assert_eq!(a[i].is_finite(), fin & (1 << i) != 0, "is_finite lane {i}");
        }
    }

    #[test]
    fn an_rgb_block_gather_reads_each_lane_s_footprint() {
        // Every index of a table (its last block included), in lanes of
        // mixed order, in all eight lanes at once (the broadcast path)
        // and in seven lanes with any one lane apart (which must not take
        // it), against the texels themselves and the scalar read; and
        // indices outside the table (negative, past the end, NaN)
        // clamped to its first or last block, mixed and all alike.
        let (stride, texels) = (7, 37);
        let table: Vec<f32> = (0..3 * texels + 1)
            .map(|i| (i as f32).mul_add(1.5, -7.25))
            .collect();
        let blocks = texels - stride - 1;
        let texel =
            |i: usize, row: usize, col: usize, c: usize| table[3 * (i + row * stride + col) + c];
        let mixed = (0..blocks).map(|start| core::array::from_fn(|l| (start + 5 * l) % blocks));
        let alike = (0..blocks).map(|i| [i; 8]);
        let odd_one = (0..8).flat_map(|l| {
            [(3, 20), (20, 3), (0, blocks - 1)].map(|(most, one)| {
                let mut v = [most; 8];
                v[l] = one;
                v
            })
        });
        for idx in mixed.chain(alike).chain(odd_one) {
            let idx: [f32; 8] = idx.map(|i| i as f32);
            let got = f32x8::gather_rgb_block(&table, f32x8::load(&idx), stride);
            for (l, &at) in idx.iter().enumerate() {
                let i = at as usize;
                let scalar = f32::gather_rgb_block(&table, at, stride);
                for (row, col, c) in block_entries() {
                    let want = texel(i, row, col, c);
                    assert_eq!(
                        lanes(got[row][col][c])[l].to_bits(),
                        want.to_bits(),
                        "lane {l}, texel {i} + ({row}, {col}), channel {c}"
                    );
                    assert_eq!(scalar[row][col][c], want, "scalar, texel {i}");
                }
            }
        }
        let outside = [
            (
                [-3.0f32, 29.0, 1e9, f32::NAN, -0.0, 28.0, 0.0, -1e9],
                [0usize, 28, 28, 0, 0, 28, 0, 0],
            ),
            ([1e9, 29.0, 31.0, 5e8, 40.0, 28.5, 2e9, 100.0], [28; 8]),
            (
                [-1.0, f32::NAN, -1e9, 0.0, -0.0, 0.5, -7.0, f32::NAN],
                [0; 8],
            ),
        ];
        for (out, want) in outside {
            let got = f32x8::gather_rgb_block(&table, f32x8::load(&out), stride);
            for (l, &i) in want.iter().enumerate() {
                for (row, col, c) in block_entries() {
                    assert_eq!(
                        lanes(got[row][col][c])[l],
                        texel(i, row, col, c),
                        "lane {l} of {out:?}"
                    );
                }
            }
        }
    }

    /// Every (row, column, channel) of an RGB texel block.
    fn block_entries() -> impl Iterator<Item = (usize, usize, usize)> {
        (0..2).flat_map(|r| (0..2).flat_map(move |col| (0..3).map(move |c| (r, col, c))))
    }

    /// The renderer's sources never call an instruction whose result is
    /// not specified to the bit (`rcpps`/`rsqrtps` estimates: AMD and Intel
    /// processors return different values), so a frame has the same bytes
    /// on every x86-64-v3 CPU. wide's `recip`/`recip_sqrt` are those
    /// estimates.
    #[test]
    fn no_source_uses_a_cpu_dependent_estimate() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let banned = [
            ["recip", "_sqrt("].concat(),
            [".recip", "()"].concat(),
            ["_rcp", "_p"].concat(),
            ["_rcp", "_s"].concat(),
            ["_rsqrt", "_p"].concat(),
            ["_rsqrt", "_s"].concat(),
        ];
        let mut stack: Vec<_> = ["core/src", "raster/src", "npr/src", "src"]
            .iter()
            .map(|d| root.join(d))
            .collect();
        let mut files = 0;
        while let Some(dir) = stack.pop() {
            for entry in std::fs::read_dir(&dir).unwrap() {
                let path = entry.unwrap().path();
                if path.is_dir() {
                    stack.push(path);
                } else if path.extension().is_some_and(|e| e == "rs") {
                    files += 1;
                    let text = std::fs::read_to_string(&path).unwrap();
                    for b in &banned {
                        assert!(!text.contains(b.as_str()), "{} uses {b}", path.display());
                    }
                }
            }
        }
        assert!(
            files > 50,
            "found only {files} source files under {}",
            root.display()
        );
    }

    #[test]
    fn rsqrt_and_rcp_are_rounded_ieee_steps_on_every_lane_width() {
        // The reference: the same two steps in f64, rounded to f32 after
        // each (f64 has more than 2 × 24 + 2 bits, so that rounding is the
        // correctly rounded f32 result): any CPU gives these bits.
        let rsqrt_ref = |x: f32| (1.0 / ((x as f64).sqrt() as f32) as f64) as f32;
        let rcp_ref = |x: f32| (1.0 / x as f64) as f32;
        let mut worst = (0.0f64, 0.0f64);
        let mut x = 1e-30f32;
        while x < 1e30 {
            let xs: [f32; 8] = core::array::from_fn(|i| x * (1.0 + 0.123 * i as f32));
            let (rs, rc) = (
                f32x8::load(&xs).rsqrt().to_array(),
                f32x8::load(&xs).rcp().to_array(),
            );
            for i in 0..8 {
                let v = xs[i] as f64;
                worst.0 = worst.0.max((rs[i] as f64 * v.sqrt() - 1.0).abs());
                worst.1 = worst.1.max((rc[i] as f64 * v - 1.0).abs());
                assert_eq!(
                    rs[i].to_bits(),
                    rsqrt_ref(xs[i]).to_bits(),
                    "rsqrt of {}",
                    xs[i]
                );
                assert_eq!(
                    rc[i].to_bits(),
                    rcp_ref(xs[i]).to_bits(),
                    "rcp of {}",
                    xs[i]
                );
                assert_eq!(
                    rs[i].to_bits(),
                    xs[i].rsqrt().to_bits(),
                    "rsqrt lane {i} of {}",
                    xs[i]
                );
                assert_eq!(
                    rc[i].to_bits(),
                    xs[i].rcp().to_bits(),
                    "rcp lane {i} of {}",
                    xs[i]
                );
            }
            x *= 1.37;
        }
        assert!(
            worst.0 < 4e-7 && worst.1 < 4e-7,
            "relative errors {worst:?}"
        );
    }

    #[test]
    fn max_and_min_clear_nan_from_self() {
        let a = f32x8::load(&[f32::NAN, 1.0, -1.0, 0.0, f32::NAN, 2.0, 3.0, -0.0]);
        let m = a.max(f32x8::ZERO).to_array();
        for (i, v) in m.iter().enumerate() {
            let s = [f32::NAN, 1.0, -1.0, 0.0, f32::NAN, 2.0, 3.0, -0.0][i];
            assert_eq!(v.to_bits(), Real::max(s, 0.0f32).to_bits(), "lane {i}");
            assert!(!v.is_nan());
        }
    }

    #[test]
    fn mask_from_bits_round_trips() {
        for bits in 0..256u32 {
            assert_eq!(f32x8::mask_from_bits(bits).bits(), bits);
            assert_eq!(f32::mask_from_bits(bits), bits & 1 != 0);
        }
    }

    #[test]
    fn atan2_matches_f64_in_every_quadrant() {
        let mut worst = 0.0f64;
        for i in 0..720 {
            let phi = (i as f64 + 0.37) * core::f64::consts::PI / 360.0 - core::f64::consts::PI;
            for r in [1e-20f32, 1e-3, 1.0, 7.5e3] {
                let (y, x) = ((phi.sin() as f32) * r, (phi.cos() as f32) * r);
                let got = Real::atan2(f32x8::splat(y), f32x8::splat(x)).lane(3);
                let want = (y as f64).atan2(x as f64);
                worst = worst.max((got - want).abs());
            }
        }
        // 2 ulp of π in f32 is 4.8e-7.
        assert!(worst < 4.8e-7, "worst |atan2 − f64| = {worst:e}");
        assert_eq!(Real::atan2(0.0f32, 1.0), 0.0);
        assert_eq!(f32x8::ZERO.atan2(f32x8::ONE).lane(0), 0.0);
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
