//! Host-side tests of the crane model.
//!
//! [`reference`] is an independent, `std`, f64-only implementation of the hybrid crane model,
//! written directly from `docs/MODEL.md` and `model/NUMERICS.md`. It shares no code with
//! `crane-model`; the tests in `tests/` require both to produce the same f64 bits.
//! [`drive_reference`] is the same for the single-axis drive (`crane_model::Drive`), written
//! from NUMERICS.md's section "Single-axis drive". [`qemu`] runs a firmware image under
//! `qemu-system-arm` for the cross-checks.

pub mod drive_reference;
pub mod qemu;
pub mod reference;
