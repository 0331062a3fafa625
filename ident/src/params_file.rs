//! The model's parameters as a TOML file (what `crane identify` writes and `crane validate`
//! reads). Field names and units as `crane_model::Params`.

use crane_model::{AxisParams, Params};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// One drive axis (see `crane_model::AxisParams`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AxisFile {
    /// Reflected inertia `Jbar` [kg].
    pub inertia: f64,
    /// Gain `K` [N/V].
    pub gain: f64,
    /// Viscous `Dbar+` [N s/m].
    pub viscous_pos: f64,
    /// Viscous `Dbar-` [N s/m].
    pub viscous_neg: f64,
    /// Dry friction `Cbar+(p)` coefficients c0..c4 [N], p in m.
    pub dry_pos: [f64; 5],
    /// Dry friction `Cbar-(p)` coefficients c0..c4 [N].
    pub dry_neg: [f64; 5],
    /// Lower limit [m].
    pub min: f64,
    /// Upper limit [m].
    pub max: f64,
}

/// All parameters (see `crane_model::Params`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParamsFile {
    /// Payload `m_p` [kg].
    pub payload_mass: f64,
    /// Trolley `m_t` [kg].
    pub trolley_mass: f64,
    /// Rail `m_r` [kg].
    pub rail_mass: f64,
    /// Gravity [m/s^2].
    pub gravity: f64,
    /// X axis.
    pub x: AxisFile,
    /// Y axis.
    pub y: AxisFile,
    /// Rope.
    pub rope: AxisFile,
    /// `D_alpha` [kg m^2/s].
    pub damping_alpha: f64,
    /// `D_beta` [kg m^2/s].
    pub damping_beta: f64,
}

fn axis_file(a: &AxisParams) -> AxisFile {
    AxisFile {
        inertia: a.inertia,
        gain: a.gain,
        viscous_pos: a.viscous_pos,
        viscous_neg: a.viscous_neg,
        dry_pos: a.dry_pos,
        dry_neg: a.dry_neg,
        min: a.min,
        max: a.max,
    }
}

fn axis_params(a: &AxisFile) -> AxisParams {
    AxisParams {
        inertia: a.inertia,
        gain: a.gain,
        viscous_pos: a.viscous_pos,
        viscous_neg: a.viscous_neg,
        dry_pos: a.dry_pos,
        dry_neg: a.dry_neg,
        min: a.min,
        max: a.max,
    }
}

impl From<&Params> for ParamsFile {
    fn from(p: &Params) -> Self {
        ParamsFile {
            payload_mass: p.payload_mass,
            trolley_mass: p.trolley_mass,
            rail_mass: p.rail_mass,
            gravity: p.gravity,
            x: axis_file(&p.x),
            y: axis_file(&p.y),
            rope: axis_file(&p.rope),
            damping_alpha: p.damping_alpha,
            damping_beta: p.damping_beta,
        }
    }
}

impl From<&ParamsFile> for Params {
    fn from(p: &ParamsFile) -> Self {
        Params {
            payload_mass: p.payload_mass,
            trolley_mass: p.trolley_mass,
            rail_mass: p.rail_mass,
            gravity: p.gravity,
            x: axis_params(&p.x),
            y: axis_params(&p.y),
            rope: axis_params(&p.rope),
            damping_alpha: p.damping_alpha,
            damping_beta: p.damping_beta,
        }
    }
}

impl ParamsFile {
    /// TOML text.
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).unwrap_or_default()
    }

    /// Reads a parameter file; errors name the file.
    pub fn read(path: &Path) -> Result<ParamsFile, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let p: ParamsFile =
            toml::from_str(&text).map_err(|e| format!("{}: {}", path.display(), e.message()))?;
        Params::from(&p)
            .validate()
            .map_err(|e| format!("{}: {e}", path.display()))?;
        Ok(p)
    }

    /// Writes a parameter file (atomically: temporary file + rename).
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        crate::atomic::write(path, self.to_toml())
    }
}
