//! Numbers as messages and errors print them: [`Num`], the one formatter of the CLI's messages.

/// A number for people: the shortest text that reads back to the same `f64`, in exponent form
/// (`1e300`, `1.98e-20`) when `|x| < 1e-4` or `|x| >= 1e15` so that huge and tiny values are not
/// printed with hundreds of digits (the rule of the CSV files, `report::csv_number`); `-0` as `0`;
/// NaN and infinities as `NaN`, `inf`, `-inf`. Imports nothing, so every layer may use it.
#[derive(Clone, Copy, Debug)]
pub struct Num(pub f64);

impl std::fmt::Display for Num {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let x = self.0;
        if x == 0.0 {
            return f.write_str("0");
        }
        if !x.is_finite() {
            return write!(f, "{x}");
        }
        if (1e-4..1e15).contains(&x.abs()) {
            write!(f, "{x}")
        } else {
            write!(f, "{x:e}")
        }
    }
}

/// Bytes for people: `1.2 kB`, `3.4 MB`, `5.6 GB` (decimal units), `512 B`.
pub fn human_bytes(b: u64) -> String {
    let b = b as f64;
    match b {
        b if b >= 1e9 => format!("{:.1} GB", b / 1e9),
        b if b >= 1e6 => format!("{:.1} MB", b / 1e6),
        b if b >= 1e3 => format!("{:.1} kB", b / 1e3),
        b => format!("{b} B"),
    }
}

/// Seconds with one decimal (`12.3`), `-0.0` (an empty sum of floats) printed as `0.0`.
pub fn seconds(x: f64) -> String {
    format!("{:.1}", x + 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn huge_and_tiny_numbers_are_short_and_read_back() {
        assert_eq!(Num(1e300).to_string(), "1e300");
        assert_eq!(Num(1.98e-20).to_string(), "1.98e-20");
        assert_eq!(
            Num(0.041666666666666664).to_string(),
            "0.041666666666666664"
        );
        assert_eq!(Num(-0.0).to_string(), "0");
        assert_eq!(Num(f64::NAN).to_string(), "NaN");
        assert_eq!(Num(f64::NEG_INFINITY).to_string(), "-inf");
        for x in [1e300, 1.98e-20, 0.05, 123456.789, 5e-324, f64::MAX] {
            assert_eq!(Num(x).to_string().parse::<f64>().unwrap(), x);
            assert!(Num(x).to_string().len() <= 24, "{}", Num(x));
        }
        assert_eq!(seconds(-0.0), "0.0");
        assert_eq!(seconds([].iter().sum::<f64>()), "0.0");
    }
}
