//! The model's parameters as a TOML file (what `crane identify` writes and `crane validate`
//! reads): exactly `crane_model::Params`, through its `serde` derives (field names and units
//! as there), so there is one parameter type. Reading checks the syntax, the model's rules
//! ([`Params::validate`]) and plausible magnitudes ([`plausible`]); every error names the file,
//! the line and the field. The fields are those of the model's table
//! ([`crane_model::params::PARAM_FIELDS`]); what is this file's own is its TOML layout (the
//! serde derives: the axes as tables `[x]`, `[y]`, `[rope]`, a polynomial as one array) and
//! the plausible magnitudes.

use crate::num::Num;
use crane_model::params::{param_entries, ParamField, PARAM_FIELDS};
use crane_model::{Axis, Params};
use std::path::{Path, PathBuf};

/// The parameter file's contents: the model's own parameter type.
pub type ParamsFile = Params;

/// Longest part of an offending TOML value echoed in an error message [characters].
const MAX_ECHO: usize = 200;

/// Why a parameter file was refused.
#[derive(Debug, thiserror::Error)]
pub enum ParamsError {
    /// The file could not be read.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// Not TOML of the expected shape (unknown or missing field, wrong type...).
    #[error("{}:{line}:{column}: {message}", path.display())]
    Syntax {
        /// The file.
        path: PathBuf,
        /// Line (1-based).
        line: usize,
        /// Column (1-based).
        column: usize,
        /// What is wrong (shortened to a few hundred characters).
        message: String,
    },
    /// A value breaks the model's rules.
    #[error("{}:{line}: {}", path.display(), describe(error))]
    Invalid {
        /// The file.
        path: PathBuf,
        /// Line of the field (1-based; 0 if it could not be found).
        line: usize,
        /// The field, its problem and value.
        error: crane_model::Error,
    },
    /// A value beyond the plausible magnitudes of [`plausible`].
    #[error("{}:{line}: `{}` = {} is beyond the plausible magnitude {} (a wrong unit?)", path.display(), error.field, Num(error.value), Num(*max))]
    Implausible {
        /// The file.
        path: PathBuf,
        /// Line of the field (1-based; 0 if it could not be found).
        line: usize,
        /// The field and its value.
        error: crane_model::Error,
        /// The largest magnitude accepted there.
        max: f64,
    },
}

/// The model's message for `e` with its value written short ([`Num`]: `1e308`, not 309
/// digits).
fn describe(e: &crane_model::Error) -> String {
    let long = e.value.to_string();
    let short = Num(e.value).to_string();
    let text = e.to_string();
    if long == short {
        text
    } else {
        text.replace(&long, &short)
    }
}

/// Coefficients of a dry-friction polynomial (`c0 .. c4`).
pub use crane_model::params::DRY_COEFFICIENTS;

/// The keys of the polynomials inside an axis table (`dry_pos`, `dry_neg`), in table order.
fn polynomial_keys() -> Vec<&'static str> {
    let mut keys = Vec::new();
    for f in PARAM_FIELDS.iter().filter(|f| f.coefficient == Some(0)) {
        if !keys.contains(&f.key) {
            keys.push(f.key);
        }
    }
    keys
}

/// Every `dry_pos` / `dry_neg` array must have exactly [`DRY_COEFFICIENTS`] entries (a longer
/// one would otherwise be cut without a word).
fn check_polynomial_lengths(path: &Path, text: &str) -> Result<(), ParamsError> {
    let Ok(table) = text.parse::<toml::Table>() else {
        return Ok(()); // the typed parse reports the syntax error with its place
    };
    let keys = polynomial_keys();
    for (axis, v) in &table {
        let Some(t) = v.as_table() else { continue };
        for &key in &keys {
            if let Some(a) = t.get(key).and_then(|a| a.as_array()) {
                if a.len() != DRY_COEFFICIENTS {
                    let field = format!("{axis}.{key}");
                    let line = text
                        .lines()
                        .position(|l| {
                            l.trim_start()
                                .strip_prefix(key)
                                .is_some_and(|r| r.trim_start().starts_with('='))
                        })
                        .map_or(0, |i| i + 1);
                    return Err(ParamsError::Syntax {
                        path: path.to_path_buf(),
                        line,
                        column: 1,
                        message: format!(
                            "`{field}` has {} coefficients; a dry-friction polynomial has \
                             exactly {DRY_COEFFICIENTS} (c0 + c1 p + ... + c4 p^4; write 0 for \
                             the terms you do not use)",
                            a.len()
                        ),
                    });
                }
            }
        }
    }
    Ok(())
}

/// TOML text of `p` (the format `read` takes).
pub fn to_toml(p: &Params) -> String {
    toml::to_string_pretty(p).unwrap_or_default()
}

/// Parses parameter-file text; `path` names the file in errors.
pub fn parse(path: &Path, text: &str) -> Result<Params, ParamsError> {
    check_polynomial_lengths(path, text)?;
    let p: Params = toml::from_str(text).map_err(|e| {
        let (line, column) = e
            .span()
            .map(|s| line_column(text, s.start))
            .unwrap_or((0, 0));
        let mut message = e.message().trim().to_string();
        if message.chars().count() > MAX_ECHO {
            message = message.chars().take(MAX_ECHO).collect::<String>() + "...";
        }
        ParamsError::Syntax {
            path: path.to_path_buf(),
            line,
            column,
            message,
        }
    })?;
    p.validate().map_err(|error| ParamsError::Invalid {
        path: path.to_path_buf(),
        line: line_of_field(text, error.field),
        error,
    })?;
    plausible(&p).map_err(|error| ParamsError::Implausible {
        path: path.to_path_buf(),
        line: line_of_field(text, error.field),
        max: max_magnitude(error.field),
        error,
    })?;
    Ok(p)
}

/// Reads and checks a parameter file; beyond [`parse`], every dry-friction polynomial must
/// be >= 0 on its axis's travel ([`nonnegative_on_travel`]).
pub fn read(path: &Path) -> Result<Params, ParamsError> {
    let text = crate::input::read_text(path).map_err(|source| ParamsError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let p = parse(path, &text)?;
    nonnegative_on_travel(&p).map_err(|error| ParamsError::Invalid {
        path: path.to_path_buf(),
        line: line_of_field(text.as_str(), error.field),
        error,
    })?;
    Ok(p)
}

/// Every dry-friction polynomial >= 0 at [`DRY_CHECK_POINTS`] + 1 points of its axis's
/// travel `[min, max]`: below 0 the model clamps it to 0 without a word, so a file that asks
/// for it is refused. (Not part of [`parse`]: a `Params` built in Python may hold any
/// polynomial, and the model's clamp is its documented meaning there.)
pub fn nonnegative_on_travel(p: &Params) -> Result<(), crane_model::Error> {
    // every polynomial of the table (an axis' `dry_pos`, `dry_neg`), at its first coefficient
    for f in PARAM_FIELDS.iter().filter(|f| f.coefficient == Some(0)) {
        let Some(axis) = f.axis else { continue };
        let a = p.axis(axis);
        let mut c = [0.0; DRY_COEFFICIENTS];
        for (c, e) in c.iter_mut().zip(param_entries(f.path)) {
            *c = (e.get)(p);
        }
        // a dry-friction polynomial below 0 somewhere on the travel: the model would clamp
        // it to 0 there without a word
        let lowest = (0..=DRY_CHECK_POINTS)
            .map(|k| {
                let p = a.min + (a.max - a.min) * k as f64 / DRY_CHECK_POINTS as f64;
                crane_model::friction::horner(&c, p)
            })
            .fold(f64::INFINITY, f64::min);
        if lowest < 0.0 {
            return Err(crane_model::Error {
                field: f.path,
                problem: crane_model::Problem::LevelBelowZero,
                value: lowest,
            });
        }
    }
    Ok(())
}

/// Writes a parameter file atomically (temporary file + rename).
pub fn write(path: &Path, p: &Params) -> std::io::Result<()> {
    crate::atomic::write(path, to_toml(p))
}

/// Largest magnitude accepted for masses [kg], inertias [kg], gains [N/V], viscous and dry
/// friction [N s/m, N], swing damping [kg m^2/s] and limits [m]: far beyond any crane this
/// model is for, far below what overflows its arithmetic.
pub const MAX_MAGNITUDE: f64 = 1e6;
/// Points (plus one) on each axis's travel `[min, max]` where the dry-friction polynomials
/// must be >= 0.
pub const DRY_CHECK_POINTS: usize = 200;

/// Largest gravity accepted [m/s^2].
pub const MAX_GRAVITY: f64 = 100.0;

/// The parameter bounded by [`MAX_GRAVITY`] (the others by [`MAX_MAGNITUDE`]).
const GRAVITY: &str = "gravity";

/// The largest magnitude accepted for the field at dotted `path` (units of the field).
fn max_magnitude(path: &str) -> f64 {
    if path == GRAVITY {
        MAX_GRAVITY
    } else {
        MAX_MAGNITUDE
    }
}

/// Plausible magnitudes (beyond [`Params::validate`]'s rules): every value at most
/// [`MAX_MAGNITUDE`], gravity at most [`MAX_GRAVITY`]. The error names the field (a
/// polynomial as a whole: `x.dry_pos`) with `Problem::TooLarge`. Order: gravity, the other
/// scalars of `Params`, then per axis its scalars and then its polynomials.
pub fn plausible(p: &Params) -> Result<(), crane_model::Error> {
    let too_large = |f: &ParamField| {
        let value = (f.get)(p);
        if value.abs() > max_magnitude(f.path) {
            Err(crane_model::Error {
                field: f.path,
                problem: crane_model::Problem::TooLarge,
                value,
            })
        } else {
            Ok(())
        }
    };
    let own = PARAM_FIELDS.iter().filter(|f| f.axis.is_none());
    let gravity_first = own.clone().filter(|f| f.path == GRAVITY);
    for f in gravity_first.chain(own.filter(|f| f.path != GRAVITY)) {
        too_large(f)?;
    }
    for axis in Axis::ALL {
        let of_axis = PARAM_FIELDS.iter().filter(|f| f.axis == Some(axis));
        let scalars = of_axis.clone().filter(|f| f.coefficient.is_none());
        for f in scalars.chain(of_axis.filter(|f| f.coefficient.is_some())) {
            too_large(f)?;
        }
    }
    Ok(())
}

/// 1-based line and column of byte `offset` in `text`.
fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, column)
}

/// 1-based line of a dotted field (`"gravity"`, `"x.viscous_pos"`, `"rope.dry_neg[2]"`) in
/// parameter-file text: the line of its key inside its table (`[x]`), or of the table as
/// `x.viscous_pos = ...` or an inline table; 0 if not found.
pub fn line_of_field(text: &str, field: &str) -> usize {
    let field = field.split('[').next().unwrap_or(field);
    let (table, key) = match field.split_once('.') {
        Some((t, k)) => (Some(t), k),
        None => (None, field),
    };
    let mut current: Option<String> = None;
    let key_of = |line: &str| -> Option<String> {
        let (k, _) = line.split_once('=')?;
        Some(k.trim().trim_matches('"').to_string())
    };
    for (i, raw) in text.lines().enumerate() {
        let line = raw.trim();
        if line.starts_with('[') {
            current = Some(
                line.trim_matches(|c| c == '[' || c == ']')
                    .trim()
                    .to_string(),
            );
            continue;
        }
        let Some(k) = key_of(line) else { continue };
        let hit = match (table, current.as_deref()) {
            (None, None) => k == key,
            (Some(t), Some(c)) => c == t && k == key,
            (Some(t), None) => k == format!("{t}.{key}") || k == t,
            (None, Some(_)) => false,
        };
        if hit {
            return i + 1;
        }
    }
    0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_field_of_the_models_table_is_a_key_of_the_file() {
        // The table's dotted paths are the serde field names: each is found in the written
        // file, at its line, with its value (a polynomial's coefficient at its index).
        let mut p = Params::default();
        for (i, f) in PARAM_FIELDS.iter().enumerate() {
            *(f.get_mut)(&mut p) = 0.5 + i as f64;
        }
        let text = to_toml(&p);
        let table: toml::Table = text.parse().unwrap();
        for f in &PARAM_FIELDS {
            let mut v = &table[f.path.split('.').next().unwrap()];
            if f.axis.is_some() {
                v = &v[f.key];
            }
            if let Some(k) = f.coefficient {
                v = &v[k];
            }
            assert_eq!(v.as_float(), Some((f.get)(&p)), "{}", f.name);
            assert_ne!(line_of_field(&text, f.name), 0, "{}", f.name);
        }
        assert!(PARAM_FIELDS.iter().any(|f| f.path == GRAVITY));
        assert_eq!(polynomial_keys(), ["dry_pos", "dry_neg"]);
    }

    #[test]
    fn plausible_names_gravity_then_scalars_then_each_axis_scalars_before_polynomials() {
        let first = |p: &Params| plausible(p).err().map(|e| e.field);
        let mut p = Params::default();
        assert_eq!(first(&p), None);
        p.rope.dry_neg[4] = 2e6;
        assert_eq!(first(&p), Some("rope.dry_neg"));
        p.rope.max = 2e6;
        assert_eq!(first(&p), Some("rope.max"));
        p.y.dry_pos[0] = -2e6;
        assert_eq!(first(&p), Some("y.dry_pos"));
        p.x.max = 2e6;
        assert_eq!(first(&p), Some("x.max"));
        p.damping_beta = 2e6;
        assert_eq!(first(&p), Some("damping_beta"));
        p.payload_mass = 2e6;
        assert_eq!(first(&p), Some("payload_mass"));
        p.gravity = 101.0;
        assert_eq!(first(&p), Some("gravity"));
        assert_eq!(max_magnitude("gravity"), MAX_GRAVITY);
        assert_eq!(max_magnitude("x.dry_pos"), MAX_MAGNITUDE);
    }

    #[test]
    fn round_trip_is_exact() {
        let p = Params::default();
        let q = parse(Path::new("p.toml"), &to_toml(&p)).unwrap();
        assert_eq!(p, q);
    }

    #[test]
    fn errors_name_file_line_and_field() {
        let text = to_toml(&Params::default());
        let bad = text.replacen("gain = 3.2", "gain = -3.2", 1);
        let e = parse(Path::new("p.toml"), &bad).unwrap_err();
        let line = bad
            .lines()
            .position(|l| l.starts_with("gain = -3.2"))
            .unwrap()
            + 1;
        let msg = e.to_string();
        assert!(msg.starts_with(&format!("p.toml:{line}: ")), "{msg}");
        assert!(msg.contains("x.gain"), "{msg}");

        let bad = text.replacen("gravity = 9.81", "gravity = 1e308", 1);
        let msg = parse(Path::new("p.toml"), &bad).unwrap_err().to_string();
        assert!(msg.contains("gravity") && msg.contains("p.toml:"), "{msg}");

        let huge = format!("{text}\nnonsense = \"{}\"\n", "z".repeat(10_000_000));
        let msg = parse(Path::new("p.toml"), &huge).unwrap_err().to_string();
        assert!(msg.len() < 1000, "echoed {} bytes", msg.len());
        assert!(msg.contains("nonsense"), "{msg}");
    }

    #[test]
    fn polynomials_of_the_wrong_length_or_negative_on_the_travel_are_refused() {
        let p = Params::default();
        let text = to_toml(&p);
        let x0 = format!("{:?}", p.x.dry_pos[0]);
        // 100 coefficients: refused, not cut to 5
        let long = format!("[{}]", vec!["0.5"; 100].join(", "));
        let start = text.find("dry_pos = [").unwrap();
        let end = start + text[start..].find(']').unwrap() + 1;
        let bad = format!("{}dry_pos = {long}{}", &text[..start], &text[end..]);
        let msg = parse(Path::new("p.toml"), &bad).unwrap_err().to_string();
        assert!(
            msg.contains("x.dry_pos") && msg.contains("100 coefficients"),
            "{msg}"
        );
        // a polynomial below 0 on the travel: refused, not clamped
        let neg = format!(
            "{}dry_pos = [-1.0, 0.0, 0.0, 0.0, 0.0]{}",
            &text[..start],
            &text[end..]
        );
        assert!(
            parse(Path::new("p.toml"), &neg).is_ok(),
            "parse keeps the model's clamp"
        );
        let dir = std::env::temp_dir().join(format!("crane-params-neg-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("p.toml");
        std::fs::write(&f, &neg).unwrap();
        let msg = read(&f).unwrap_err().to_string();
        assert!(
            msg.contains("x.dry_pos") && msg.contains("negative"),
            "{msg} ({x0})"
        );
        std::fs::write(&f, &text).unwrap();
        assert_eq!(read(&f).unwrap(), p);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
