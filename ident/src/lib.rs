//! Identification of the crane model (placeholder).
