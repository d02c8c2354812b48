//! Fixed-point screen coordinates.
//!
//! Vertices snap to 1/256 pixel (8 fractional bits). After clipping, every
//! vertex lies inside the guard band |x|, |y| ≤ GUARD_BAND_PX, so a snapped
//! coordinate needs |X| ≤ 2²⁰·2⁸ = 2²⁸. Edge coefficients are differences
//! (|A|, |B| ≤ 2²⁹), C = −(A·X0 + B·Y0) stays under 2⁵⁸, and an edge value
//! A·X + B·Y + C under 2⁶⁰: setup and span math are i64 and cannot overflow.
//! `Target::new` limits images to MAX_DIM pixels, far inside the band.

/// Fractional bits of a snapped coordinate.
pub(crate) const SUBPIXEL_BITS: u32 = 8;
/// One pixel in fixed-point units.
pub const SUBPIXEL_ONE: i64 = 1 << SUBPIXEL_BITS;
/// Half a pixel: pixel centres sit at x·256 + 128.
pub(crate) const SUBPIXEL_HALF: i64 = SUBPIXEL_ONE / 2;
/// Half-width of the guard band in pixels, measured from the image origin.
pub(crate) const GUARD_BAND_PX: f64 = (1u64 << 20) as f64;

/// Snaps a screen coordinate (pixels) to fixed point, rounding to nearest
/// (ties to even: one `roundsd`, where `round`'s ties-away is a libm call).
/// The caller guarantees |v| ≤ GUARD_BAND_PX (clipping does).
#[inline]
pub fn snap(v: f64) -> i64 {
    (v * SUBPIXEL_ONE as f64).round_ties_even() as i64
}

/// Fixed-point coordinate of the centre of pixel `i`.
#[inline]
pub fn pixel_centre(i: i64) -> i64 {
    i * SUBPIXEL_ONE + SUBPIXEL_HALF
}
