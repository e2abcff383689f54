//! Writing results: atomic files, CSV tables and the run summary.

pub mod atomic;
pub mod outdir;
pub mod plot;
pub mod run_output;
pub mod style;

pub use atomic::AtomicFile;
pub use outdir::{Manifest, OutDir};

/// FNV-1a, 64 bits, as 16 hex digits (a content tag, not a security measure).
pub fn fnv1a(bytes: &[u8]) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    format!("{h:016x}")
}
