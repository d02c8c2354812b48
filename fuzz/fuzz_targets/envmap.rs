//! Fuzz target `envmap`: see specula::fuzzing::envmap for the input and
//! the checks (a broken guarantee panics there).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let _ = specula::fuzzing::envmap(data);
});
