//! What the fuzz targets' mutation tests share: a fixed random sequence,
//! the seed corpus of a target, and running one mutated input through its
//! entry point with a crash saved for replay.

use std::path::Path;

/// xorshift64*: a fixed sequence, so every run tries the same inputs.
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    /// A number below `n` (0 for `n` = 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// The `seed-*` files of fixtures/fuzz/`target`, sorted by path: (path,
/// bytes).
pub fn seeds(target: &str) -> Vec<(String, Vec<u8>)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures/fuzz")
        .join(target);
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
    assert!(!seeds.is_empty(), "no seeds in {}", dir.display());
    seeds
}

/// Runs `data` (round `round`'s mutation of seed `name`) through the
/// fuzz entry point `entry` of `target`: whether it was accepted. A panic
/// (a broken guarantee) saves the input to the temporary folder and fails
/// the test naming it.
pub fn run(
    target: &str,
    entry: fn(&[u8]) -> Result<(), String>,
    name: &str,
    round: usize,
    data: &[u8],
) -> bool {
    match std::panic::catch_unwind(|| entry(data)) {
        Ok(r) => r.is_ok(),
        Err(_) => {
            let out = std::env::temp_dir().join(format!("{target}-mutation-crash"));
            std::fs::write(&out, data).unwrap();
            panic!(
                "a mutation of {name} (round {round}) broke a guarantee; the input is in {}",
                out.display()
            );
        }
    }
}
