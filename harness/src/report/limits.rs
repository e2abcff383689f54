//! The limits a scene is held to before it runs: its estimated memory and outputs against
//! [`OUTPUT_LIMIT_BYTES`], refused with an input error that names the key to change unless the
//! caller allows it. The words for "show the estimate" and "run anyway" are the caller's
//! ([`LimitWords`]: a command-line flag, a Python argument). The engine estimates
//! ([`MemoryEstimate`], [`OutputEstimate`]); what a tool accepts is the tool's.

use grainchain_engine::format::human_bytes;
use grainchain_engine::{InputError, MemoryEstimate, OutputEstimate};
use std::path::Path;

/// An estimate's refusal over [`OUTPUT_LIMIT_BYTES`].
pub trait Refusal {
    /// The input error that refuses the scene at `path` over the limit (naming the key to
    /// change and `words.allow`), or `None` under it.
    fn refusal(&self, path: &Path, words: LimitWords) -> Option<InputError>;
}

/// The most a scene may write (its estimated outputs) or hold (its estimated memory) before it
/// is refused unless allowed: 1 GB.
pub const OUTPUT_LIMIT_BYTES: u64 = 1_000_000_000;

/// Grains beyond which the scene check refuses a chain anyway (its message is the check's): the
/// whole chain's, striker and target included, as [`MemoryEstimate::grains`] counts them.
const CHECKED_GRAINS: u64 = grainchain_engine::MAX_GRAINS as u64;

/// How a caller names the estimate and the way to run anyway, for the refusals' messages.
#[derive(Clone, Copy, Debug)]
pub struct LimitWords {
    /// Where the estimate is shown (`` `grainchain check` ``).
    pub check: &'static str,
    /// What runs anyway (`--allow-large-output`).
    pub allow: &'static str,
}

impl Refusal for MemoryEstimate {
    /// The refusal of a simulation estimated above [`OUTPUT_LIMIT_BYTES`] of memory, naming the
    /// file at `path` and the key that sets the count; `None` under the limit, or beyond the
    /// grains the scene check refuses anyway (its message says more).
    fn refusal(&self, path: &Path, words: LimitWords) -> Option<InputError> {
        (self.bytes > OUTPUT_LIMIT_BYTES && self.grains <= CHECKED_GRAINS).then(|| {
            InputError::Invalid {
                file: path.to_path_buf(),
                key: self.key.clone(),
                message: format!(
                    "{} grains would need about {} of memory (estimated upper bound, {} bytes \
                     per grain with {}), over the limit of {}; use fewer grains, or pass {}",
                    self.grains,
                    human_bytes(self.bytes),
                    self.per_grain,
                    self.method.name(),
                    human_bytes(OUTPUT_LIMIT_BYTES),
                    words.allow
                ),
            }
        })
    }
}

impl Refusal for OutputEstimate {
    /// The refusal of outputs estimated above [`OUTPUT_LIMIT_BYTES`], naming the file at `path`
    /// and the key of the larger file; `None` under the limit.
    fn refusal(&self, path: &Path, words: LimitWords) -> Option<InputError> {
        (self.total_bytes() > OUTPUT_LIMIT_BYTES).then(|| InputError::Invalid {
            file: path.to_path_buf(),
            key: self.largest().0.to_string(),
            message: format!(
                "the outputs would take about {} (estimated; {} shows the estimate), over the \
                 limit of {}; write fewer snapshots or grains, or pass {}",
                human_bytes(self.total_bytes()),
                words.check,
                human_bytes(OUTPUT_LIMIT_BYTES),
                words.allow
            ),
        })
    }
}
