//! Numbers in messages: short whatever their magnitude.

use std::fmt;

/// Displays a value in Rust's shortest round-trip form when it is zero, not finite, or
/// between 1e-4 and 1e6 in magnitude (`0.25`, `3600`), and in scientific notation otherwise
/// (`1e308` rather than a 309-digit integer, `1.5e-7`). For every number an error message
/// echoes back.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Num(pub f64);

impl fmt::Display for Num {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let v = self.0;
        if v == 0.0 || !v.is_finite() || (1e-4..1e6).contains(&v.abs()) {
            write!(f, "{v}")
        } else {
            write!(f, "{v:e}")
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Num;

    #[test]
    fn huge_and_tiny_values_print_short() {
        assert_eq!(Num(1e308).to_string(), "1e308");
        assert_eq!(Num(-1.5e-7).to_string(), "-1.5e-7");
        assert_eq!(Num(0.2499775091938441).to_string(), "0.2499775091938441");
        assert_eq!(Num(3600.0).to_string(), "3600");
        assert_eq!(Num(0.0).to_string(), "0");
        assert_eq!(Num(f64::NAN).to_string(), "NaN");
        assert!(Num(f64::MAX).to_string().len() < 30);
    }
}
