//! The envmap fuzz target's guarantees (no panic; texels, derived data and
//! pixels finite) over deterministic mutations of its seed corpus: bytes
//! changed (header digits and signs among them), cut off, or repeated, run
//! through the same entry point the fuzzer runs
//! (specula::fuzzing::envmap). A cheap stand-in for a libFuzzer run that
//! `cargo test` repeats every time.

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
        (self.next() % n.max(1) as u64) as usize
    }
}

#[test]
fn mutated_envmap_seeds_never_break_a_guarantee() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/fuzz/envmap");
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
            match std::panic::catch_unwind(|| specula::fuzzing::envmap(&data)) {
                Ok(r) => accepted += usize::from(r.is_ok()),
                Err(_) => {
                    let out = std::env::temp_dir().join("envmap-mutation-crash");
                    std::fs::write(&out, &data).unwrap();
                    panic!(
                        "a mutation of {name} (round {round}) broke a guarantee; the input is in {}",
                        out.display()
                    );
                }
            }
        }
    }
    eprintln!("{tried} mutated inputs, {accepted} accepted");
}
