//! Parameters to and from the TOML files of the `crane` CLI.
//!
//! The only place that knows how parameters are (de)serialised: through
//! `crane_ident::params_file` (serde on `crane_model::Params`), so a file the CLI writes is
//! read here and the other way round.

use crane_model::Params;
use std::path::Path;

/// Parses and validates a parameter file's text; `origin` (a path or `"<string>"`) prefixes
/// every message, and TOML errors carry their line and the field.
pub fn parse(text: &str, origin: &str) -> Result<Params, String> {
    crane_ident::params_file::parse(Path::new(origin), text).map_err(|e| e.to_string())
}

/// The TOML text of `params`, as `crane identify` writes it.
pub fn render(params: &Params) -> Result<String, String> {
    Ok(crane_ident::params_file::to_toml(params))
}
