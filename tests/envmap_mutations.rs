//! The envmap fuzz target's guarantees (no panic; texels, derived data and
//! pixels finite) over deterministic mutations of its seed corpus: bytes
//! changed (header digits and signs among them), cut off, or repeated, run
//! through the same entry point the fuzzer runs
//! (specula::fuzzing::envmap). A cheap stand-in for a libFuzzer run that
//! `cargo test` repeats every time.

mod common;

use common::mutate::{run, seeds, Rng};

#[test]
fn mutated_envmap_seeds_never_break_a_guarantee() {
    let seeds = seeds("envmap");
    let replacements: &[u8] = b"0123456789-+ XY\n\xff\x00\x7f\x80";
    let mut rng = Rng(0x2545_f491_4f6c_dd1d);
    let (mut tried, mut accepted) = (0, 0);
    for round in 0..120 {
        for (name, seed) in &seeds {
            let mut data = seed.clone();
            match round % 3 {
                0 => {
                    for _ in 0..1 + rng.below(3) {
                        let at = rng.below(data.len());
                        data[at] = replacements[rng.below(replacements.len())];
                    }
                }
                1 => {
                    for _ in 0..1 + rng.below(4) {
                        let at = rng.below(data.len());
                        data[at] = rng.next() as u8;
                    }
                }
                _ => {
                    let at = rng.below(data.len());
                    if rng.below(2) == 0 {
                        data.truncate(at);
                    } else {
                        let piece = data[at..].to_vec();
                        data.extend_from_slice(&piece);
                    }
                }
            }
            tried += 1;
            accepted += usize::from(run("envmap", specula::fuzzing::envmap, name, round, &data));
        }
    }
    eprintln!("{tried} mutated inputs, {accepted} accepted");
}
