//! The block bounds: before a block of [`BLOCK`] samples is measured,
//! a bound over its values drops every source whose measure cannot
//! exceed its threshold there ([`block_sources`]), so flat ground and the
//! insides of large faces are not measured; [`detect_block`] measures the
//! rest.

use super::detect::{detect_lanes, load8, Field, Thresholds};
use super::measure::W;
use specula_core::Real;
use wide::f32x8;

/// Samples [`detect_block`] takes at once.
pub(super) const BLOCK: usize = 64;

/// [`detect_lanes`] on the 64 samples x..x+64 of a row (bit i: sample
/// x + i; 1 ≤ x, x + 65 ≤ width). Each field row's 66 values are sliced
/// once, and the eight chunks read them at constant offsets: no bounds
/// checks inside (slicing chunk by chunk was a large share of the
/// detection's instructions).
#[inline(never)]
pub(super) fn detect_block(
    f: &[&[f32]; 6],
    used: [bool; 6],
    t: &Thresholds,
    rows: [usize; 3],
    x: usize,
) -> u64 {
    const UNUSED: [f32; BLOCK + 2] = [0.0; BLOCK + 2];
    let row = |k: usize, r: usize| -> &[f32; BLOCK + 2] {
        if used[k] {
            <&[f32; BLOCK + 2]>::try_from(&f[k][rows[r] + x - 1..rows[r] + x + BLOCK + 1])
                .unwrap_or(&UNUSED)
        } else {
            &UNUSED
        }
    };
    // Written out: an array `map` here was left as a call.
    let rows3 = |k: usize| [row(k, 0), row(k, 1), row(k, 2)];
    let a = [rows3(0), rows3(1), rows3(2), rows3(3), rows3(4), rows3(5)];
    let Some(t) = block_sources(t, &a) else {
        return 0;
    };
    let t = &t;
    let mut bits = 0u64;
    for i in 0..BLOCK / 8 {
        let o = 8 * i;
        let at = |f: Field| {
            let a = &a[f as usize];
            let load = |r: usize, c: usize| {
                f32x8::from(<[f32; 8]>::try_from(&a[r][o + c..o + c + 8]).unwrap_or_default())
            };
            [
                [load(0, 0), load(0, 1), load(0, 2)],
                [load(1, 0), load(1, 1), load(1, 2)],
                [load(2, 0), load(2, 1), load(2, 2)],
            ]
        };
        bits |= u64::from(detect_lanes(t, at)) << o;
    }
    bits
}

/// A block's three rows of one field ([`detect_block`]).
pub(super) type BlockRows<'a> = [&'a [f32; BLOCK + 2]; 3];

/// The sources of `t` that may mark a sample of a block whose field rows
/// are `a` (`None`: none may, the block has no mark). A source is dropped
/// where a bound over the whole block shows that its measure, as
/// [`detect_lanes`] rounds it, cannot exceed its threshold at any sample:
/// a flat floor, the inside of a large face. The sources are tested in the
/// order id, normal, depth, colour (cheapest and most often failing
/// first), up to the first that may mark: the rest are kept untested.
#[inline(always)]
pub(super) fn block_sources(t: &Thresholds, a: &[BlockRows; 6]) -> Option<Thresholds> {
    let lane0 = |v: f32x8| v.as_array()[0];
    let mut out = *t;
    'tests: {
        if let Some(ti) = t.id {
            if !(one_label(&a[Field::Label as usize]) && lane0(ti) >= 0.0) {
                break 'tests;
            }
            out.id = None; // every measure is 0, not above ti ≥ 0
        }
        if let Some(tn) = t.normal {
            let mut g2 = 0.0f32;
            for f in [Field::NormalX, Field::NormalY, Field::NormalZ] {
                let b = gradient_bound(&a[f as usize]);
                g2 += b * b + b * b; // detect_lanes' sum: increasing in each term
                let under = g2 <= lane0(tn); // false for a NaN bound
                if !under {
                    break 'tests;
                }
            }
            out.normal = None;
        }
        if let Some(td) = t.depth {
            let under = depth_bound(&a[Field::InvDepth as usize]) <= lane0(td);
            if !under {
                break 'tests;
            }
            out.depth = None;
        }
        if let Some(tc) = t.color {
            let b = gradient_bound(&a[Field::Luma as usize]);
            let under = b * b + b * b <= lane0(tc);
            if !under {
                break 'tests;
            }
            out.color = None;
        }
    }
    let any = out.depth.is_some() || out.normal.is_some() || out.id.is_some();
    (any || out.color.is_some()).then_some(out)
}

/// Offsets of the 8-value loads that cover a block row's BLOCK + 2 values.
const COVER8: [usize; BLOCK / 8 + 1] = {
    let mut o = [BLOCK + 2 - 8; BLOCK / 8 + 1];
    let mut k = 0;
    while k < BLOCK / 8 {
        o[k] = 8 * k;
        k += 1;
    }
    o
};

/// The least and greatest value of a block's rows, NaNs left out (+∞, −∞
/// if every value is NaN). [`Real::min`] and `max` give their second
/// operand when the first is NaN, and the running extremes never are.
#[inline(always)]
fn block_range(rows: &BlockRows) -> (f32, f32) {
    let mut lo = f32x8::splat(f32::INFINITY);
    let mut hi = f32x8::splat(f32::NEG_INFINITY);
    for row in rows {
        for o in COVER8 {
            let v = load8(&row[o..o + 8]);
            lo = Real::min(v, lo);
            hi = Real::max(v, hi);
        }
    }
    let lo = lo
        .as_array()
        .iter()
        .fold(f32::INFINITY, |m, &v| Real::min(v, m));
    let hi = hi
        .as_array()
        .iter()
        .fold(f32::NEG_INFINITY, |m, &v| Real::max(v, m));
    (lo, hi)
}

/// Whether every label of a block's rows is the first (a NaN label is
/// unequal to all, as in [`detect_lanes`]' unordered ≠).
#[inline(always)]
fn one_label(rows: &BlockRows) -> bool {
    let first = f32x8::splat(rows[0][0]);
    let mut differ = f32x8::ZERO;
    for row in rows {
        for o in COVER8 {
            let v = load8(&row[o..o + 8]);
            differ |= v.simd_ne(first);
        }
    }
    !differ.any()
}

/// An upper bound of |Gx| and |Gy|
/// ([`gradient8`](super::detect::gradient8)) at every sample of a block,
/// as rounded in f32 (NaN or +∞ when none can be given): with the
/// values in [lo, hi] each difference is at most D = hi − lo in magnitude
/// (rounding is monotone), so each Sobel sum is at most its sum with D in
/// every difference, rounded in the same order. NaN values are left out:
/// a difference with one is NaN, and a NaN g² is above no threshold.
#[inline(always)]
fn gradient_bound(rows: &BlockRows) -> f32 {
    let (lo, hi) = block_range(rows);
    let d = hi - lo; // −∞ if every value is NaN: its square +∞ tests false
    W[0] * d + W[1] * d + W[2] * d
}

/// An upper bound of the depth measure ([`detect_lanes`]) at every sample
/// of a block, as rounded in f32 (NaN or +∞ when none can be given).
/// With q in [lo, hi] each second difference q₊ + q₋ − 2q is at most
/// E = 2hi − 2lo in magnitude, so |dxx| and |dyy| are at most their sums
/// with E (rounding is monotone), and a sample's q_max is ≥ lo: the
/// measure is ≤ that bound / lo when lo > 0, and 0 (q_max ≤ 0) when
/// hi ≤ 0. NaN values are left out as in [`gradient_bound`]: a q_max is
/// NaN (no mark) or one of the others, ≥ lo.
#[inline(always)]
fn depth_bound(rows: &BlockRows) -> f32 {
    let (lo, hi) = block_range(rows);
    if hi <= 0.0 {
        return 0.0;
    }
    let e = (hi + hi) - 2.0 * lo;
    let b = W[0] * e + W[1] * e + W[2] * e;
    if lo > 0.0 {
        b / lo
    } else {
        f32::NAN
    }
}
