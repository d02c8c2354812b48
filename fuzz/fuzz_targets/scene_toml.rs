//! Fuzz target `scene_toml`: see specula::fuzzing::scene_toml for the input layout and
//! the checks (a broken guarantee panics there).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let _ = specula::fuzzing::scene_toml(data);
});
