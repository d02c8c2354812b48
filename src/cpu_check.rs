//! A binary built for x86-64-v3 (.cargo/config.toml) refuses, with a clear
//! message and exit status 1, to run on a CPU without those instructions,
//! instead of dying with SIGILL at the first one.
//!
//! The check must run before any code of ours that the compiler may have
//! given AVX instructions, and with target-cpu=x86-64-v3 that is any of
//! it: even main's prologue may zero a struct with a ymm register. So it
//! is an ELF constructor (`.init_array`), which the loader runs before the
//! Rust runtime calls main, and it does nothing the compiler could
//! vectorise: the cpuid instruction and a few bit tests, then on failure
//! libc's write(2) and _exit with a byte string. tests/portability.rs runs the binary under
//! `qemu-x86_64-static -cpu Nehalem` (no AVX) to check exactly this.
//!
//! Compiled only when the build enables AVX2 (on other targets and with
//! `RUSTFLAGS="-C target-cpu=native"` on an older CPU there is nothing to
//! check).

#[cfg(all(target_arch = "x86_64", target_os = "linux", target_feature = "avx2"))]
mod imp {
    #[used]
    #[unsafe(link_section = ".init_array")]
    static CHECK: extern "C" fn() = check;

    extern "C" {
        fn write(fd: i32, buf: *const u8, count: usize) -> isize;
        fn _exit(status: i32) -> !;
    }

    const MESSAGE: &[u8] = b"error: this specula binary was built for x86-64-v3 CPUs (AVX2, FMA, BMI1/2, F16C, LZCNT, MOVBE) and this CPU lacks some of them.\n\
Build it for this machine instead: RUSTFLAGS=\"-C target-cpu=native\" cargo build --release (see the README, \"Other CPUs\").\n";

    /// CPUID bits of x86-64-v3 (Intel SDM vol. 2A, CPUID), and whether the
    /// OS saves the ymm registers (XCR0 bits 1 and 2). Read with the cpuid
    /// instruction itself: std's `is_x86_feature_detected!` answers `true`
    /// without asking the CPU when the crate is compiled with the feature.
    #[allow(unused_unsafe)]
    fn has_x86_64_v3() -> bool {
        use std::arch::x86_64::{__cpuid, __cpuid_count, _xgetbv};
        let bit = |r: u32, b: u32| r >> b & 1 == 1;
        // SAFETY: cpuid exists on every x86-64 CPU; leaves above the
        // highest one reported are not read.
        let (max, max_ext) = unsafe { (__cpuid(0).eax, __cpuid(0x8000_0000).eax) };
        if max < 7 || max_ext < 0x8000_0001 {
            return false;
        }
        // SAFETY: as above; leaves 1 and 7 are at most `max` and
        // 0x8000_0001 at most `max_ext`, checked just before.
        let (l1, l7, ext) = unsafe { (__cpuid(1), __cpuid_count(7, 0), __cpuid(0x8000_0001)) };
        let cpu = bit(l1.ecx, 12) // FMA
            && bit(l1.ecx, 22) // MOVBE
            && bit(l1.ecx, 26) // XSAVE
            && bit(l1.ecx, 27) // OSXSAVE
            && bit(l1.ecx, 28) // AVX
            && bit(l1.ecx, 29) // F16C
            && bit(l7.ebx, 3) // BMI1
            && bit(l7.ebx, 5) // AVX2
            && bit(l7.ebx, 8) // BMI2
            && bit(ext.ecx, 5); // LZCNT
                                // SAFETY: xgetbv is valid once OSXSAVE is set, checked just above.
        cpu && unsafe { _xgetbv(0) } & 0b110 == 0b110
    }

    extern "C" fn check() {
        let ok = has_x86_64_v3();
        if !ok {
            // SAFETY: write(2) reads MESSAGE.len() bytes from a static;
            // _exit ends the process without running anything else of ours.
            unsafe {
                write(2, MESSAGE.as_ptr(), MESSAGE.len());
                _exit(1);
            }
        }
    }
}
