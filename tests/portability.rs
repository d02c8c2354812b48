//! The x86-64-v3 binary on a CPU without AVX: a clear error and exit
//! status 1, not SIGILL (src/cpu_check.rs). Runs the binary under qemu's
//! user-mode emulator with a Nehalem CPU (SSE4.2, no AVX); skipped, with
//! the reason printed, where qemu-x86_64-static is not installed (Debian:
//! apt-get install qemu-user-static; .ci/run installs it).

use std::io::Write;
use std::process::{Command, Stdio};

const QEMU: &str = "qemu-x86_64-static";

fn qemu_available() -> bool {
    Command::new(QEMU)
        .arg("--version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// Runs `specula eval` on one line under qemu with `cpu`: (exit code or
/// None for a signal, stdout, stderr).
fn eval_on(cpu: &str) -> (Option<i32>, String, String) {
    let mut child = Command::new(QEMU)
        .args(["-cpu", cpu, env!("CARGO_BIN_EXE_specula"), "eval"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run qemu");
    child
        .stdin
        .take()
        .unwrap()
        .write_all(br#"{"material": {"model": "lambert", "base_color": [1, 1, 1]}, "wi": [0, 0, 1], "wo": [0, 0, 1]}"#)
        .unwrap();
    let out = child.wait_with_output().unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

#[test]
fn cpu_without_avx2_gets_a_clear_error() {
    if !cfg!(all(target_arch = "x86_64", target_feature = "avx2")) {
        eprintln!("skipped: this build does not target x86-64-v3, nothing to check");
        return;
    }
    if !qemu_available() {
        eprintln!("skipped: {QEMU} not installed (apt-get install qemu-user-static)");
        return;
    }
    // The same binary on an emulated CPU that has AVX2 and FMA answers, so
    // the emulator runs it and the check does not refuse good CPUs.
    let (code, out, err) = eval_on("max");
    assert_eq!(code, Some(0), "under -cpu max: {err}");
    assert!(out.starts_with("{\"f\":[0.318"), "{out}");
    // Nehalem: no AVX. Exit status 1 (a signal gives None; SIGILL was what
    // happened before the check) and the message says why and what to do.
    let (code, out, err) = eval_on("Nehalem");
    assert_eq!(
        code,
        Some(1),
        "under -cpu Nehalem: status {code:?}, stderr {err}"
    );
    assert!(out.is_empty(), "{out}");
    assert!(err.contains("x86-64-v3") && err.contains("AVX2"), "{err}");
    assert!(err.contains("target-cpu=native"), "{err}");
}
