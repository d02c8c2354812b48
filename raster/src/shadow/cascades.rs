//! A directional light's cascades: maps along the view's depth, split by
//! the practical split scheme (a blend of logarithmic and uniform split
//! depths). Each cascade's map is fitted in `shadow_pass/fit.rs`; a shaded point
//! picks its cascade by its view depth (`lookup.rs`).

/// Largest number of cascades of a directional light.
pub(crate) const MAX_CASCADES: u32 = 4;

/// The practical split scheme's blend between logarithmic (1) and uniform
/// (0) split depths.
pub(crate) const CASCADE_LAMBDA: f32 = 0.75;

/// The `count − 1` view depths between `count` cascades over the view
/// depths `near..far`: the practical split scheme, a blend by
/// [`CASCADE_LAMBDA`] of the logarithmic split near·(far/near)^(i/count)
/// and the uniform one near + (far − near)·i/count.
pub(crate) fn cascade_splits(count: u32, near: f32, far: f32) -> Vec<f32> {
    if !(far > 0.0 && far.is_finite()) {
        return vec![0.0; count.saturating_sub(1) as usize];
    }
    // At most 1e6 between near and far, so the powers stay finite.
    let near = near.max(far * 1e-6).min(far);
    (1..count)
        .map(|i| {
            let t = i as f32 / count as f32;
            let log = near * (far / near).powf(t);
            let uniform = near + (far - near) * t;
            CASCADE_LAMBDA * log + (1.0 - CASCADE_LAMBDA) * uniform
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The split depths of 4 cascades over 1..10000: the logarithmic ones
    /// are 10, 100 and 1000, the uniform ones 2500.75, 5000.5 and
    /// 7500.25, blended 3 : 1.
    #[test]
    fn cascade_splits_blend_log_and_uniform() {
        let s = cascade_splits(4, 1.0, 10000.0);
        let want = [
            0.75 * 10.0 + 0.25 * 2500.75,
            0.75 * 100.0 + 0.25 * 5000.5,
            0.75 * 1000.0 + 0.25 * 7500.25,
        ];
        assert_eq!(s.len(), 3);
        for (g, w) in s.iter().zip(want) {
            assert!((g - w).abs() <= 1e-3 * w, "{s:?} vs {want:?}");
        }
        assert!(cascade_splits(1, 0.1, 50.0).is_empty());
        // Increasing and inside the range for any near/far.
        for (n, f) in [
            (0.1, 50.0),
            (1e-6, 1e6),
            (3.0, 3.0),
            (0.0, 10.0),
            (1.0, 0.0),
        ] {
            let s = cascade_splits(4, n, f);
            assert!(s.windows(2).all(|w| w[0] <= w[1]), "{s:?}");
            assert!(s.iter().all(|z| z.is_finite() && *z <= f), "{s:?}");
        }
    }
}
