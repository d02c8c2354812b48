//! The bytes and bits the drawing leaves behind, with no tiny-skia types:
//! a draw's [`Coverage`] (its alpha bytes as row spans), the nonzero
//! stretches of a row of alpha ([`push_runs`]), and the runs of a row's
//! touched 8-pixel chunks ([`runs`]).

/// One draw's coverage: the alpha bytes its fill leaves on a transparent
/// mask, over the pixels it changed, as row spans (rows ascending).
#[derive(Debug, Default)]
pub(super) struct Coverage {
    /// Per span: its row, its first pixel, and where its bytes start in
    /// `alpha` (they end where the next span's start).
    pub(super) spans: Vec<[u32; 3]>,
    pub(super) alpha: Vec<u8>,
}

impl Coverage {
    /// The spans of rows [lo, hi): (row, first pixel, alpha bytes).
    pub(super) fn rows(
        &self,
        lo: usize,
        hi: usize,
    ) -> impl Iterator<Item = (usize, usize, &[u8])> + '_ {
        let first = self.spans.partition_point(|s| (s[0] as usize) < lo);
        let last = self.spans.partition_point(|s| (s[0] as usize) < hi);
        (first..last).map(move |i| {
            let [y, x, at] = self.spans[i];
            let end = self
                .spans
                .get(i + 1)
                .map_or(self.alpha.len(), |s| s[2] as usize);
            (y as usize, x as usize, &self.alpha[at as usize..end])
        })
    }
}

/// Appends the nonzero stretches of `row` (image row `y`, starting at
/// pixel `x0`) to `c`: runs of 8-byte chunks holding a nonzero byte,
/// trimmed to their first and last nonzero bytes; and clears them, leaving
/// `row` all zero.
pub(super) fn push_runs(c: &mut Coverage, row: &mut [u8], y: u32, x0: u32) {
    // A whole chunk read as one u64 (the last, short one byte by byte).
    let nonzero = |row: &[u8], k: usize| match row.get(k * 8..k * 8 + 8) {
        Some(chunk) => u64::from_ne_bytes(chunk.try_into().unwrap_or([0; 8])) != 0,
        None => row[k * 8..].iter().any(|&a| a != 0),
    };
    let chunks = row.len().div_ceil(8);
    let mut k = 0;
    while k < chunks {
        if !nonzero(row, k) {
            k += 1;
            continue;
        }
        let start = k;
        while k < chunks && nonzero(row, k) {
            k += 1;
        }
        let end = (k * 8).min(row.len());
        let run = &mut row[start * 8..end];
        let first = run.iter().position(|&a| a != 0).unwrap_or(0);
        let last = run.iter().rposition(|&a| a != 0).unwrap_or(first);
        c.spans
            .push([y, x0 + (start * 8 + first) as u32, c.alpha.len() as u32]);
        c.alpha.extend_from_slice(&run[first..=last]);
        run.fill(0);
    }
}

/// The runs of set bits of a row's chunk marks (`row`, 64 chunks a word)
/// as pixel ranges of a `w`-pixel row, left to right.
pub(super) fn runs(row: &[u64], w: usize) -> impl Iterator<Item = std::ops::Range<usize>> + '_ {
    // Runs of set bits within each word, as chunk ranges.
    let (mut k, mut bits) = (0, row.first().copied().unwrap_or(0));
    let mut runs = std::iter::from_fn(move || loop {
        if bits != 0 {
            let c0 = bits.trailing_zeros() as usize;
            let len = (bits >> c0).trailing_ones() as usize;
            bits &= !(u64::MAX >> (64 - len) << c0);
            return Some((k * 64 + c0, k * 64 + c0 + len));
        }
        k += 1;
        bits = *row.get(k)?;
    })
    .peekable();
    // Joined where a run goes on into the next word.
    std::iter::from_fn(move || {
        let (c0, mut c1) = runs.next()?;
        while let Some((_, end)) = runs.next_if(|r| r.0 == c1) {
            c1 = end;
        }
        Some(c0 * 8..(c1 * 8).min(w))
    })
}
