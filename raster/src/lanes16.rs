//! Sixteen f32 lanes in one AVX-512 register ([`F32x16`]), for the packet
//! pairs of `packet_pairs`: every operation is the f32x8 one's per lane
//! (the same IEEE operation, the same fused multiply-adds, the same
//! NaN rule for `max` and `min`; the polynomial functions run on each
//! half as f32x8), so a lane computes the same bits in either.
//!
//! The binary is built for x86-64-v3 (AVX2): these instructions exist
//! only where the processor has AVX-512F, DQ, VL and BW. A value of this
//! type is therefore made only in code that runs after [`available`]
//! said so (`packet_pairs::shade_batch`, whose callers check it, and the
//! tests below, which check it first); that is the invariant every
//! `unsafe` block here rests on.

use crate::fragment::Fragment;
use core::arch::x86_64::*;
use core::ops::{Add, AddAssign, BitAnd, BitOr, Div, Mul, MulAssign, Neg, Not, Sub, SubAssign};
use specula_core::{f32x8, Constant, Mask, Real, V3};

/// Whether this processor runs [`F32x16`] (checked once).
pub(crate) fn available() -> bool {
    static HAS: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *HAS.get_or_init(|| {
        is_x86_feature_detected!("avx512f")
            && is_x86_feature_detected!("avx512dq")
            && is_x86_feature_detected!("avx512vl")
            && is_x86_feature_detected!("avx512bw")
    })
}

/// An AVX-512 instruction on [`F32x16`] values, which exist only where
/// the processor has AVX-512 (the module's invariant).
macro_rules! avx512 {
    ($e:expr) => {
        // SAFETY: F32x16 values, and so this code, run only after
        // `available()` found AVX-512F/DQ/VL/BW (module doc).
        unsafe { $e }
    };
}

/// Sixteen f32 lanes; see the module doc.
#[derive(Clone, Copy, Debug)]
#[repr(transparent)]
pub(crate) struct F32x16(__m512);

/// A lane mask of [`F32x16`]: bit i for lane i.
#[derive(Clone, Copy, Debug)]
pub(crate) struct M16(u16);

impl BitAnd for M16 {
    type Output = M16;
    #[inline(always)]
    fn bitand(self, o: M16) -> M16 {
        M16(self.0 & o.0)
    }
}

impl BitOr for M16 {
    type Output = M16;
    #[inline(always)]
    fn bitor(self, o: M16) -> M16 {
        M16(self.0 | o.0)
    }
}

impl Not for M16 {
    type Output = M16;
    #[inline(always)]
    fn not(self) -> M16 {
        M16(!self.0)
    }
}

impl Mask for M16 {
    #[inline(always)]
    fn any(self) -> bool {
        self.0 != 0
    }
    #[inline(always)]
    fn all(self) -> bool {
        self.0 == u16::MAX
    }
    #[inline(always)]
    fn bits(self) -> u32 {
        self.0 as u32
    }
}

/// Lanes 0–7 of `v`.
#[inline(always)]
pub(crate) fn v3_lo(v: &V3<F32x16>) -> V3<f32x8> {
    V3::new(v.x.lo(), v.y.lo(), v.z.lo())
}

/// Lanes 8–15 of `v`.
#[inline(always)]
pub(crate) fn v3_hi(v: &V3<F32x16>) -> V3<f32x8> {
    V3::new(v.x.hi(), v.y.hi(), v.z.hi())
}

/// Lanes 0–7 (`HI` false) or 8–15 (`HI` true) of every field of `f`.
#[inline(always)]
pub(crate) fn fragment_half<const HI: bool>(f: &Fragment<F32x16>) -> Fragment<f32x8> {
    // No closures: not inlined, they would be compiled without AVX-512.
    Fragment {
        p: v3_half::<HI>(&f.p),
        n: v3_half::<HI>(&f.n),
        wo: v3_half::<HI>(&f.wo),
        w: f.w.half::<HI>(),
        b1: f.b1.half::<HI>(),
        b2: f.b2.half::<HI>(),
    }
}

/// Lanes 0–7 (`HI` false) or 8–15 (`HI` true) of `v`.
#[inline(always)]
fn v3_half<const HI: bool>(v: &V3<F32x16>) -> V3<f32x8> {
    V3::new(v.x.half::<HI>(), v.y.half::<HI>(), v.z.half::<HI>())
}

/// `a`'s lanes in the low half, `b`'s in the high one.
#[inline(always)]
pub(crate) fn v3_halves(a: V3<f32x8>, b: V3<f32x8>) -> V3<F32x16> {
    V3::new(
        F32x16::from_halves(a.x, b.x),
        F32x16::from_halves(a.y, b.y),
        F32x16::from_halves(a.z, b.z),
    )
}

impl F32x16 {
    /// Lanes 0–7 from `lo`, 8–15 from `hi`.
    #[inline(always)]
    pub(crate) fn from_halves(lo: f32x8, hi: f32x8) -> F32x16 {
        let (lo, hi): (__m256, __m256) = (bytemuck::cast(lo), bytemuck::cast(hi));
        avx512!(F32x16(_mm512_insertf32x8::<1>(
            _mm512_castps256_ps512(lo),
            hi
        )))
    }

    /// `v` in both halves.
    #[inline(always)]
    pub(crate) fn both(v: f32x8) -> F32x16 {
        F32x16::from_halves(v, v)
    }

    /// Lanes 0–7.
    #[inline(always)]
    pub(crate) fn lo(self) -> f32x8 {
        bytemuck::cast(avx512!(_mm512_castps512_ps256(self.0)))
    }

    /// Lanes 8–15.
    #[inline(always)]
    pub(crate) fn hi(self) -> f32x8 {
        bytemuck::cast(avx512!(_mm512_extractf32x8_ps::<1>(self.0)))
    }

    /// Lanes 0–7 (`HI` false) or 8–15 (`HI` true).
    #[inline(always)]
    pub(crate) fn half<const HI: bool>(self) -> f32x8 {
        if HI {
            self.hi()
        } else {
            self.lo()
        }
    }

    /// `f` on each half.
    #[inline(always)]
    fn halves(self, f: impl Fn(f32x8) -> f32x8) -> F32x16 {
        F32x16::from_halves(f(self.lo()), f(self.hi()))
    }

    /// Every lane `v`, in a constant (no instruction).
    const fn splat_const(v: f32) -> F32x16 {
        // SAFETY: __m512 is sixteen f32 lanes; any bits are a valid value.
        F32x16(unsafe { core::mem::transmute::<[f32; 16], __m512>([v; 16]) })
    }

    fn to_array(self) -> [f32; 16] {
        // SAFETY: __m512 and [f32; 16] have the same size, and any bits
        // are a valid f32.
        unsafe { core::mem::transmute::<__m512, [f32; 16]>(self.0) }
    }
}

macro_rules! arithmetic {
    ($op:ident, $f:ident, $intrinsic:ident, $op_assign:ident, $f_assign:ident) => {
        impl $op for F32x16 {
            type Output = F32x16;
            #[inline(always)]
            fn $f(self, o: F32x16) -> F32x16 {
                avx512!(F32x16($intrinsic(self.0, o.0)))
            }
        }
        impl $op_assign for F32x16 {
            #[inline(always)]
            fn $f_assign(&mut self, o: F32x16) {
                *self = $op::$f(*self, o);
            }
        }
    };
}

arithmetic!(Add, add, _mm512_add_ps, AddAssign, add_assign);
arithmetic!(Sub, sub, _mm512_sub_ps, SubAssign, sub_assign);
arithmetic!(Mul, mul, _mm512_mul_ps, MulAssign, mul_assign);

impl Div for F32x16 {
    type Output = F32x16;
    #[inline(always)]
    fn div(self, o: F32x16) -> F32x16 {
        avx512!(F32x16(_mm512_div_ps(self.0, o.0)))
    }
}

impl Neg for F32x16 {
    type Output = F32x16;
    /// The sign flipped, as f32x8's negation (an exclusive or).
    #[inline(always)]
    fn neg(self) -> F32x16 {
        avx512!(F32x16(_mm512_xor_ps(self.0, _mm512_set1_ps(-0.0))))
    }
}

impl Real for F32x16 {
    type Mask = M16;
    const LANES: usize = 16;
    const EXACT: bool = false;
    const ZERO: Self = F32x16::splat_const(0.0);
    const ONE: Self = F32x16::splat_const(1.0);
    const HALF: Self = F32x16::splat_const(0.5);
    const PI: Self = F32x16::splat_const(core::f32::consts::PI);
    const FRAC_1_PI: Self = F32x16::splat_const(core::f32::consts::FRAC_1_PI);

    #[inline(always)]
    fn splat(v: f64) -> Self {
        avx512!(F32x16(_mm512_set1_ps(v as f32)))
    }
    #[inline(always)]
    fn constant(c: Constant) -> Self {
        F32x16::both(<f32x8 as Real>::constant(c))
    }
    #[inline(always)]
    fn load(s: &[f32]) -> Self {
        let a: &[f32; 16] = s[..16].try_into().expect("slice of 16");
        // The pointer is to 16 readable f32 (no alignment needed).
        avx512!(F32x16(_mm512_loadu_ps(a.as_ptr())))
    }
    #[inline(always)]
    fn store(self, out: &mut [f32]) {
        out[..16].copy_from_slice(&self.to_array());
    }
    #[inline(always)]
    fn lane_index() -> Self {
        Self::load(&core::array::from_fn::<f32, 16, _>(|i| i as f32))
    }
    #[inline(always)]
    fn lane(self, i: usize) -> f64 {
        self.to_array()[i] as f64
    }
    #[inline(always)]
    fn mask_from_bits(bits: u32) -> M16 {
        M16(bits as u16)
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        avx512!(F32x16(_mm512_sqrt_ps(self.0)))
    }
    #[inline(always)]
    fn rsqrt(self) -> Self {
        Self::ONE / self.sqrt()
    }
    #[inline(always)]
    fn rcp(self) -> Self {
        Self::ONE / self
    }
    #[inline(always)]
    fn mul_add(self, a: Self, b: Self) -> Self {
        avx512!(F32x16(_mm512_fmadd_ps(self.0, a.0, b.0)))
    }
    /// `vmaxps self, o`: `o` where either is NaN or both are zero, as
    /// f32x8's `max`.
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        avx512!(F32x16(_mm512_max_ps(self.0, o.0)))
    }
    /// `vminps self, o`, as [`F32x16::max`].
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        avx512!(F32x16(_mm512_min_ps(self.0, o.0)))
    }
    #[inline(always)]
    fn abs(self) -> Self {
        avx512!(F32x16(_mm512_abs_ps(self.0)))
    }
    #[inline(always)]
    fn floor(self) -> Self {
        const FLOOR: i32 = _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC;
        avx512!(F32x16(_mm512_roundscale_ps::<FLOOR>(self.0)))
    }
    #[inline(always)]
    fn exp(self) -> Self {
        self.halves(|v| v.exp())
    }
    #[inline(always)]
    fn ln(self) -> Self {
        self.halves(|v| v.ln())
    }
    #[inline(always)]
    fn exp_m1(self) -> Self {
        self.halves(Real::exp_m1)
    }
    #[inline(always)]
    fn ln_1p(self) -> Self {
        self.halves(Real::ln_1p)
    }
    #[inline(always)]
    fn atan2(self, x: Self) -> Self {
        F32x16::from_halves(
            Real::atan2(self.lo(), x.lo()),
            Real::atan2(self.hi(), x.hi()),
        )
    }
    #[inline(always)]
    fn lt(self, o: Self) -> M16 {
        avx512!(M16(_mm512_cmp_ps_mask::<_CMP_LT_OQ>(self.0, o.0)))
    }
    #[inline(always)]
    fn le(self, o: Self) -> M16 {
        avx512!(M16(_mm512_cmp_ps_mask::<_CMP_LE_OQ>(self.0, o.0)))
    }
    #[inline(always)]
    fn gt(self, o: Self) -> M16 {
        avx512!(M16(_mm512_cmp_ps_mask::<_CMP_GT_OQ>(self.0, o.0)))
    }
    #[inline(always)]
    fn ge(self, o: Self) -> M16 {
        avx512!(M16(_mm512_cmp_ps_mask::<_CMP_GE_OQ>(self.0, o.0)))
    }
    /// Finite: an exponent field not all ones.
    #[inline(always)]
    fn is_finite(self) -> M16 {
        avx512!({
            let exponent = _mm512_set1_epi32(0x7F80_0000);
            let bits = _mm512_and_si512(_mm512_castps_si512(self.0), exponent);
            M16(!_mm512_cmpeq_epi32_mask(bits, exponent))
        })
    }
    #[inline(always)]
    fn select(m: M16, a: Self, b: Self) -> Self {
        avx512!(F32x16(_mm512_mask_blend_ps(m.0, b.0, a.0)))
    }
    #[inline(always)]
    fn gather(table: &[f32], index: Self) -> Self {
        F32x16::from_halves(
            <f32x8 as Real>::gather(table, index.lo()),
            <f32x8 as Real>::gather(table, index.hi()),
        )
    }
    /// f32x8's blocks on each half, read in sixteen lanes at once: the
    /// same clamp of the indices, then one 16-byte load a texel into a
    /// quarter of a register and one 4 × 4 transpose per 128-bit quarter
    /// ([`rgb_channels`]), or the twelve floats broadcast when all sixteen
    /// lanes read one block.
    #[inline(always)]
    fn gather_rgb_block(table: &[f32], index: Self, stride: usize) -> [[[Self; 3]; 2]; 2] {
        let texels = table.len().saturating_sub(1) / 3;
        assert!(texels >= stride.saturating_add(2));
        let last = (texels - (stride + 2)).min(i32::MAX as usize) as i32;
        let i = avx512!(_mm512_min_epi32(
            _mm512_max_epi32(_mm512_cvttps_epi32(index.0), _mm512_setzero_si512()),
            _mm512_set1_epi32(last),
        ));
        let first = avx512!(_mm_cvtsi128_si32(_mm512_castsi512_si128(i)));
        let same = avx512!(_mm512_cmpeq_epi32_mask(i, _mm512_set1_epi32(first))) == u16::MAX;
        // Each lane's block starts at float 3 × index of the top row and
        // of the row below it.
        let top = table.as_ptr();
        // SAFETY: texels ≥ stride + 2 (asserted), so the row below starts
        // within the table.
        let below = unsafe { top.add(3 * stride) };
        // SAFETY: every lane is at most texels − stride − 2 (clamped), so
        // the texels at offsets 0, 1, stride and stride + 1 from it are at
        // most texel texels − 1, which starts at float 3 texels − 3: its
        // 16 bytes end at float 3 texels, within the table (at least
        // 3 texels + 1 floats); the loads need no alignment. AVX-512 as
        // `avx512!`.
        unsafe {
            if same {
                // Neighbouring pixels reading a coarse level, mostly.
                let at = first as usize * 3;
                let (a, b) = (top.add(at), below.add(at));
                return [
                    [broadcast_rgb(a), broadcast_rgb(a.add(3))],
                    [broadcast_rgb(b), broadcast_rgb(b.add(3))],
                ];
            }
            let mut lanes = [0i32; 16];
            _mm512_storeu_si512(lanes.as_mut_ptr().cast(), i);
            [
                [rgb_channels(top, &lanes, 0), rgb_channels(top, &lanes, 3)],
                [
                    rgb_channels(below, &lanes, 0),
                    rgb_channels(below, &lanes, 3),
                ],
            ]
        }
    }
}

/// The three floats at `at`, each in every lane.
///
/// # Safety
/// `at..at + 3` is readable; AVX-512 as [`F32x16`]'s module says.
#[inline(always)]
unsafe fn broadcast_rgb(at: *const f32) -> [F32x16; 3] {
    [
        F32x16(_mm512_set1_ps(*at)),
        F32x16(_mm512_set1_ps(*at.add(1))),
        F32x16(_mm512_set1_ps(*at.add(2))),
    ]
}

/// The 16 bytes at float `row + 3 × lanes[l] + offset`.
///
/// # Safety
/// They are readable.
#[inline(always)]
unsafe fn texel(row: *const f32, lanes: &[i32; 16], l: usize, offset: usize) -> __m128 {
    _mm_loadu_ps(row.add(3 * lanes[l] as usize + offset))
}

/// The RGB texel at float `row + 3 × lanes[l] + offset` of each lane l,
/// as three channels. Each texel is one 16-byte load into a 128-bit
/// quarter: quarter q of register k holds lane 4q + k, so that a 4 × 4
/// transpose within each quarter (four unpacks, then a shuffle a
/// channel) leaves lane l in position l.
///
/// # Safety
/// Each lane's 16 bytes are readable; AVX-512 as [`F32x16`]'s module
/// says.
#[inline(always)]
unsafe fn rgb_channels(row: *const f32, lanes: &[i32; 16], offset: usize) -> [F32x16; 3] {
    let mut quarters = [_mm512_setzero_ps(); 4];
    for (k, q) in quarters.iter_mut().enumerate() {
        let v = _mm512_castps128_ps512(texel(row, lanes, k, offset));
        let v = _mm512_insertf32x4::<1>(v, texel(row, lanes, k + 4, offset));
        let v = _mm512_insertf32x4::<2>(v, texel(row, lanes, k + 8, offset));
        *q = _mm512_insertf32x4::<3>(v, texel(row, lanes, k + 12, offset));
    }
    let [a, b, c, d] = quarters;
    // Per quarter: [r_a r_b g_a g_b] and [b_a b_b · ·], and so for c, d.
    let (ab_lo, ab_hi) = (_mm512_unpacklo_ps(a, b), _mm512_unpackhi_ps(a, b));
    let (cd_lo, cd_hi) = (_mm512_unpacklo_ps(c, d), _mm512_unpackhi_ps(c, d));
    [
        F32x16(_mm512_shuffle_ps::<0b01_00_01_00>(ab_lo, cd_lo)),
        F32x16(_mm512_shuffle_ps::<0b11_10_11_10>(ab_lo, cd_lo)),
        F32x16(_mm512_shuffle_ps::<0b01_00_01_00>(ab_hi, cd_hi)),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Values that take every rule's edge: signed zeros, infinities, NaN,
    /// subnormals, the largest finite, halves (floor), and ordinary ones.
    const SPECIAL: [f32; 16] = [
        0.0,
        -0.0,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
        1.0e-40,
        -1.0e-40,
        f32::MAX,
        -2.5,
        2.5,
        0.5,
        -0.5,
        1.0,
        3.7,
        -123.456,
        1.0e-20,
    ];

    /// Sixteen lanes of `seed`-dependent values, special ones among them.
    fn lanes(seed: u32) -> [f32; 16] {
        core::array::from_fn(|i| {
            let k = (seed as usize * 7 + i * 5) % 16;
            if seed.is_multiple_of(3) {
                SPECIAL[k]
            } else {
                let x = (seed as f32 * 0.618_034 + i as f32 * 1.37).sin()
                    * 10f32.powi((i % 7) as i32 - 3);
                if k < 4 {
                    SPECIAL[k]
                } else {
                    x
                }
            }
        })
    }

    fn x16(a: [f32; 16]) -> F32x16 {
        F32x16::load(&a)
    }

    fn halves(a: [f32; 16]) -> (f32x8, f32x8) {
        (
            <f32x8 as Real>::load(&a[..8]),
            <f32x8 as Real>::load(&a[8..]),
        )
    }

    fn same(got: F32x16, lo: f32x8, hi: f32x8, what: &str) {
        let got = got.to_array();
        let want: Vec<f32> = lo.to_array().into_iter().chain(hi.to_array()).collect();
        for i in 0..16 {
            // NaN payloads are compared too: the same operation gives the
            // same NaN.
            assert_eq!(
                got[i].to_bits(),
                want[i].to_bits(),
                "{what}, lane {i}: {} vs {}",
                got[i],
                want[i]
            );
        }
    }

    /// Every operation of F32x16 against f32x8's on each half, bit for
    /// bit, over special and ordinary values. Skipped (with a message)
    /// where the processor has no AVX-512.
    #[test]
    fn every_operation_matches_f32x8_bit_for_bit() {
        if !available() {
            eprintln!("skipped: this processor has no AVX-512F/DQ/VL/BW");
            return;
        }
        for seed in 0..64 {
            let (a, b, c) = (lanes(seed), lanes(seed + 1000), lanes(seed + 77));
            let (va, vb, vc) = (x16(a), x16(b), x16(c));
            let (a0, a1) = halves(a);
            let (b0, b1) = halves(b);
            let (c0, c1) = halves(c);
            same(va + vb, a0 + b0, a1 + b1, "add");
            same(va - vb, a0 - b0, a1 - b1, "sub");
            same(va * vb, a0 * b0, a1 * b1, "mul");
            same(va / vb, a0 / b0, a1 / b1, "div");
            same(-va, -a0, -a1, "neg");
            same(va.sqrt(), Real::sqrt(a0), Real::sqrt(a1), "sqrt");
            same(va.rsqrt(), Real::rsqrt(a0), Real::rsqrt(a1), "rsqrt");
            same(va.rcp(), Real::rcp(a0), Real::rcp(a1), "rcp");
            same(
                va.mul_add(vb, vc),
                Real::mul_add(a0, b0, c0),
                Real::mul_add(a1, b1, c1),
                "mul_add",
            );
            same(va.max(vb), Real::max(a0, b0), Real::max(a1, b1), "max");
            same(va.min(vb), Real::min(a0, b0), Real::min(a1, b1), "min");
            same(va.abs(), Real::abs(a0), Real::abs(a1), "abs");
            same(Real::floor(va), Real::floor(a0), Real::floor(a1), "floor");
            same(va.exp(), Real::exp(a0), Real::exp(a1), "exp");
            same(va.ln(), Real::ln(a0), Real::ln(a1), "ln");
            same(va.exp_m1(), Real::exp_m1(a0), Real::exp_m1(a1), "exp_m1");
            same(va.ln_1p(), Real::ln_1p(a0), Real::ln_1p(a1), "ln_1p");
            same(
                va.atan2(vb),
                Real::atan2(a0, b0),
                Real::atan2(a1, b1),
                "atan2",
            );
            same(
                va.clamp(vb, vc),
                Real::clamp(a0, b0, c0),
                Real::clamp(a1, b1, c1),
                "clamp",
            );
            let masks = [
                (va.lt(vb), Real::lt(a0, b0), Real::lt(a1, b1)),
                (va.le(vb), Real::le(a0, b0), Real::le(a1, b1)),
                (va.gt(vb), Real::gt(a0, b0), Real::gt(a1, b1)),
                (va.ge(vb), Real::ge(a0, b0), Real::ge(a1, b1)),
                (va.is_finite(), Real::is_finite(a0), Real::is_finite(a1)),
            ];
            for (k, (m, m0, m1)) in masks.into_iter().enumerate() {
                assert_eq!(
                    m.bits(),
                    m0.bits() | m1.bits() << 8,
                    "mask {k}, seed {seed}"
                );
                same(
                    F32x16::select(m, vb, vc),
                    <f32x8 as Real>::select(m0, b0, c0),
                    <f32x8 as Real>::select(m1, b1, c1),
                    "select",
                );
            }
            for &v in &SPECIAL {
                let w = <f32x8 as Real>::splat(v as f64);
                same(F32x16::splat(v as f64), w, w, "splat");
            }
            let c = Constant::new(seed as f64 * 0.1);
            let w = <f32x8 as Real>::constant(c);
            same(F32x16::constant(c), w, w, "constant");
        }
        same(
            F32x16::ONE,
            <f32x8 as Real>::ONE,
            <f32x8 as Real>::ONE,
            "ONE",
        );
        same(F32x16::PI, <f32x8 as Real>::PI, <f32x8 as Real>::PI, "PI");
        let w = <f32x8 as Real>::FRAC_1_PI;
        same(F32x16::FRAC_1_PI, w, w, "FRAC_1_PI");
        same(
            F32x16::HALF,
            <f32x8 as Real>::HALF,
            <f32x8 as Real>::HALF,
            "HALF",
        );
        same(
            F32x16::ZERO,
            <f32x8 as Real>::ZERO,
            <f32x8 as Real>::ZERO,
            "ZERO",
        );
    }

    #[test]
    fn halves_masks_and_gathers_keep_their_lanes() {
        if !available() {
            eprintln!("skipped: this processor has no AVX-512F/DQ/VL/BW");
            return;
        }
        let a = lanes(5);
        let (a0, a1) = halves(a);
        let v = F32x16::from_halves(a0, a1);
        same(v, a0, a1, "from_halves");
        same(F32x16::both(a1), a1, a1, "both");
        assert_eq!(
            v.lo().to_array().map(f32::to_bits),
            a0.to_array().map(f32::to_bits)
        );
        assert_eq!(
            v.hi().to_array().map(f32::to_bits),
            a1.to_array().map(f32::to_bits)
        );
        for bits in [0u32, 1, 0x8000, 0x00FF, 0xFF00, 0xFFFF, 0x1234] {
            let m = F32x16::mask_from_bits(bits);
            assert_eq!(m.bits(), bits);
            assert_eq!(m.any(), bits != 0);
            assert_eq!(m.all(), bits == 0xFFFF);
        }
        let mut out = [0.0f32; 16];
        v.store(&mut out);
        assert_eq!(out.map(f32::to_bits), a.map(f32::to_bits));
        assert_eq!(F32x16::lane_index().lane(13), 13.0);
        let table: Vec<f32> = (0..100).map(|i| i as f32 * 0.5).collect();
        let index: [f32; 16] = core::array::from_fn(|i| (i * 6) as f32);
        let (i0, i1) = halves(index);
        same(
            F32x16::gather(&table, x16(index)),
            <f32x8 as Real>::gather(&table, i0),
            <f32x8 as Real>::gather(&table, i1),
            "gather",
        );
        let block = F32x16::gather_rgb_block(&table, x16(index.map(|i| i / 6.0)), 5);
        let (g0, g1) = (
            <f32x8 as Real>::gather_rgb_block(&table, i0 / <f32x8 as Real>::splat(6.0), 5),
            <f32x8 as Real>::gather_rgb_block(&table, i1 / <f32x8 as Real>::splat(6.0), 5),
        );
        for (r, c, k) in
            (0..2).flat_map(|r| (0..2).flat_map(move |c| (0..3).map(move |k| (r, c, k))))
        {
            same(block[r][c][k], g0[r][c][k], g1[r][c][k], "gather_rgb_block");
        }
    }

    /// The sixteen-lane block read against f32x8's on each half, bit for
    /// bit: distinct blocks, one block in all lanes (the broadcast), one
    /// in a half only, one lane apart at each position, and indices the
    /// clamp moves (negative, NaN, infinite, past the last block,
    /// fractional), some of them into one block.
    #[test]
    fn rgb_blocks_match_f32x8_on_each_half() {
        if !available() {
            eprintln!("skipped: this processor has no AVX-512F/DQ/VL/BW");
            return;
        }
        let stride = 9;
        let texels = stride * (stride - 1);
        let table: Vec<f32> = (0..3 * texels + 1)
            .map(|i| (i as f32).sin() * 7.0)
            .collect();
        let last = (texels - stride - 2) as f32;
        let mut patterns: Vec<[f32; 16]> = vec![
            core::array::from_fn(|l| (l * 3) as f32),
            [5.0; 16],
            core::array::from_fn(|l| if l < 8 { 11.0 } else { l as f32 }),
            core::array::from_fn(|l| if l < 8 { l as f32 * 2.5 } else { 0.0 }),
            core::array::from_fn(|l| SPECIAL[l]),
            core::array::from_fn(|l| last - 3.0 + l as f32 * 0.75),
            // One block only after the clamp: the broadcast.
            core::array::from_fn(|l| [-3.0, f32::NAN, -0.5, 0.0][l % 4]),
            core::array::from_fn(|l| last + l as f32),
        ];
        // One lane reading another block, at each position.
        for odd in 0..16 {
            patterns.push(core::array::from_fn(|l| if l == odd { 20.0 } else { 7.0 }));
        }
        for index in patterns {
            let (i0, i1) = halves(index);
            let block = F32x16::gather_rgb_block(&table, x16(index), stride);
            let g0 = <f32x8 as Real>::gather_rgb_block(&table, i0, stride);
            let g1 = <f32x8 as Real>::gather_rgb_block(&table, i1, stride);
            for (r, c, k) in
                (0..2).flat_map(|r| (0..2).flat_map(move |c| (0..3).map(move |k| (r, c, k))))
            {
                same(block[r][c][k], g0[r][c][k], g1[r][c][k], "gather_rgb_block");
            }
        }
    }
}
