//! The glTF fuzz target's guarantees (no panic, every pixel finite) over
//! deterministic mutations of its seed corpus: digits, punctuation and
//! bytes of the seeds changed one or a few at a time, run through the same
//! entry point the fuzzer runs (specula::fuzzing::gltf). A cheap stand-in
//! for a libFuzzer run that `cargo test` repeats every time.

mod common;

use common::mutate::{run, seeds, Rng};

#[test]
fn mutated_gltf_seeds_never_break_a_guarantee() {
    let seeds = seeds("gltf");
    let replacements: &[u8] = b"0123456789-.e,:[]{}\"";
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let (mut tried, mut accepted) = (0, 0);
    for round in 0..1500 {
        for (name, seed) in &seeds {
            let mut data = seed.clone();
            for _ in 0..1 + rng.below(3) {
                let at = rng.below(data.len());
                data[at] = if round % 2 == 0 {
                    replacements[rng.below(replacements.len())]
                } else {
                    rng.next() as u8
                };
            }
            tried += 1;
            accepted += usize::from(run("gltf", specula::fuzzing::gltf, name, round, &data));
        }
    }
    eprintln!("{tried} mutated inputs, {accepted} accepted");
}
