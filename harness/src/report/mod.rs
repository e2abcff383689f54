//! Writing results: atomic files, CSV tables and the run summary.

pub mod atomic;
mod journal;
pub mod limits;
pub mod outdir;
pub mod plot;
pub mod run_output;
pub mod style;

pub(crate) use atomic::AtomicFile;
pub(crate) use journal::recorded;

/// FNV-1a, 64 bits, as 16 hex digits (a content tag, not a security measure): the `fnv`
/// crate's [`fnv::FnvHasher`], fed the bytes with `Hasher::write` only (its `write_str` would
/// add a byte). [`AtomicFile`] feeds it in pieces and gets the same tag as of the whole bytes.
pub fn fnv1a(bytes: &[u8]) -> String {
    use std::hash::Hasher;
    let mut h = fnv::FnvHasher::default();
    h.write(bytes);
    format!("{:016x}", h.finish())
}

/// A number as every CSV file of grainchain writes it (CONTRIBUTING.md, "CSV conventions"):
/// the shortest text that reads back to the same `f64` (`{}`), in exponent form (`{:e}`, e.g.
/// `6e-46`, `1.5e15`) when `|x| < 1e-4` or `|x| >= 1e15` so that tiny and huge numbers are not
/// written with dozens of zeros; a value that is not a finite number (NaN, infinite) is missing:
/// the empty field.
pub fn csv_number(x: f64) -> String {
    CsvNumber(x).to_string()
}

/// [`csv_number`] as a `Display` value, for writers that should not allocate per number
/// (`write!(f, ",{}", CsvNumber(x))`).
#[derive(Clone, Copy, Debug)]
pub struct CsvNumber(pub f64);

impl std::fmt::Display for CsvNumber {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let x = self.0;
        if !x.is_finite() {
            return Ok(());
        }
        let a = x.abs();
        if a != 0.0 && !(1e-4..1e15).contains(&a) {
            write!(f, "{x:e}")
        } else {
            write!(f, "{x}")
        }
    }
}

/// [`csv_number`] as a serde field serialiser: a row struct's `f64` field with
/// `#[serde(serialize_with = "crate::report::serialize_number")]` is written as every CSV of
/// grainchain writes its numbers (empty when not finite).
pub fn serialize_number<S: serde::Serializer>(x: &f64, s: S) -> Result<S::Ok, S::Error> {
    s.collect_str(&CsvNumber(*x))
}

/// [`csv_number`] of an optional value (`None` is missing: the empty field).
pub fn csv_opt(x: Option<f64>) -> String {
    x.map_or_else(String::new, csv_number)
}

#[cfg(test)]
mod tests {
    use super::csv_number;

    /// FNV-1a 64 of the reference vectors of its specification (draft-eastlake-fnv, test
    /// suite of www.isthe.com/chongo/tech/comp/fnv): every checksum grainchain has written
    /// (journals, manifests, members, designs) keeps its value.
    #[test]
    fn fnv1a_gives_the_reference_values() {
        assert_eq!(super::fnv1a(b""), "cbf29ce484222325");
        assert_eq!(super::fnv1a(b"a"), "af63dc4c8601ec8c");
        assert_eq!(super::fnv1a(b"foobar"), "85944171f73967e8");
    }

    /// The convention's examples, and every number reads back to the same bits.
    #[test]
    fn csv_numbers_are_short_and_read_back_exactly() {
        assert_eq!(csv_number(0.0), "0");
        assert_eq!(csv_number(1.0), "1");
        assert_eq!(csv_number(-2.5), "-2.5");
        assert_eq!(csv_number(1e-4), "0.0001");
        assert_eq!(csv_number(9.99e-5), "9.99e-5");
        // ensemble.csv wrote this one as 0.000...0006 with 45 zeros.
        assert_eq!(csv_number(6e-46), "6e-46");
        assert_eq!(csv_number(123456789012345.0), "123456789012345");
        assert_eq!(csv_number(1e15), "1e15");
        assert_eq!(csv_number(f64::NAN), "");
        assert_eq!(csv_number(f64::INFINITY), "");
        let mut x: f64 = 1.2345678901234567e-300;
        while x < 1e300 {
            for y in [x, -x, x * std::f64::consts::PI, 1.0 / 3.0 * x] {
                let text = csv_number(y);
                assert!(text.len() <= 24, "{text}");
                assert_eq!(
                    text.parse::<f64>().unwrap().to_bits(),
                    y.to_bits(),
                    "{text}"
                );
            }
            x *= 7.3;
        }
        for y in [f64::MIN_POSITIVE, 5e-324, f64::MAX, -0.0, 0.1 + 0.2] {
            let text = csv_number(y);
            assert_eq!(
                text.parse::<f64>().unwrap().to_bits(),
                y.to_bits(),
                "{text}"
            );
        }
    }
}
