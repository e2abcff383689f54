//! The git revision this checkout was built from (`revision/build.rs`): a crate of its own so
//! that a commit or a checkout rebuilds only it and the few crates that print it (the
//! command-line tool and the Python module), not the engine or the harness.

/// A short hash, `<hash>-dirty` when tracked files differed from HEAD, or `unknown` when the
/// build could not tell (no git, or not a checkout).
pub const GIT: &str = env!("GRAINCHAIN_GIT");
