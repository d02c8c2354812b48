//! The glTF fuzz target's guarantees (no panic, every pixel finite) over
//! deterministic mutations of its seed corpus: digits, punctuation and
//! bytes of the seeds changed one or a few at a time, run through the same
//! entry point the fuzzer runs (specula::fuzzing::gltf). A cheap stand-in
//! for a libFuzzer run that `cargo test` repeats every time.

use std::path::Path;

/// xorshift64*: a fixed sequence, so every run tries the same inputs.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

#[test]
fn mutated_gltf_seeds_never_break_a_guarantee() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/fuzz/gltf");
    let mut seeds: Vec<(String, Vec<u8>)> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            p.file_name()
                .unwrap()
                .to_str()
                .unwrap()
                .starts_with("seed-")
        })
        .map(|p| (p.display().to_string(), std::fs::read(&p).unwrap()))
        .collect();
    seeds.sort();
    assert!(!seeds.is_empty());
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
            match std::panic::catch_unwind(|| specula::fuzzing::gltf(&data)) {
                Ok(r) => accepted += usize::from(r.is_ok()),
                Err(_) => {
                    let out = std::env::temp_dir().join("gltf-mutation-crash");
                    std::fs::write(&out, &data).unwrap();
                    panic!("a mutation of {name} (round {round}) broke a guarantee; the input is in {}", out.display());
                }
            }
        }
    }
    eprintln!("{tried} mutated inputs, {accepted} accepted");
}
