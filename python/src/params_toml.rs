//! Parameters to and from the TOML files of the `crane` CLI.
//!
//! The only place that knows how parameters are (de)serialised: today through
//! `crane_ident::params_file::ParamsFile`; when `crane_model::Params` gains its own serde
//! derives, [`parse`] and [`render`] are the two bodies to switch.

use crane_ident::params_file::ParamsFile;
use crane_model::Params;

/// Parses and validates a parameter file's text; `origin` (a path or `"<string>"`) prefixes
/// every message, and TOML errors carry their line and column.
pub fn parse(text: &str, origin: &str) -> Result<Params, String> {
    let file: ParamsFile = toml::from_str(text).map_err(|e| format!("{origin}: {e}"))?;
    let params = Params::from(&file);
    params.validate().map_err(|e| format!("{origin}: {e}"))?;
    Ok(params)
}

/// The TOML text of `params`, as `crane identify` writes it.
pub fn render(params: &Params) -> Result<String, String> {
    toml::to_string_pretty(&ParamsFile::from(params)).map_err(|e| e.to_string())
}
