//! Linker arguments of the firmware: its memory map (`memory.x`, QEMU mps2-an386) copied into
//! `OUT_DIR` as `crate-memory.x` and put on the search path, where the workspace-root
//! `memory.x` (the one cortex-m-rt's `link.x` reads: the linker looks in the workspace root
//! first) INCLUDEs it; `-Tdefmt.x` (defmt's symbol table) only with the `probe` feature;
//! `-Tlink.x` (cortex-m-rt) comes from `.cargo/config.toml` for the target.
use std::path::PathBuf;

fn main() {
    let out = PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    std::fs::copy("memory.x", out.join("crate-memory.x")).expect("copy memory.x to OUT_DIR");
    println!("cargo:rustc-link-search={}", out.display());
    if std::env::var_os("CARGO_FEATURE_PROBE").is_some() {
        println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
    }
    println!("cargo:rerun-if-changed=memory.x");
    println!("cargo:rerun-if-changed=../memory.x");
    println!("cargo:rerun-if-changed=build.rs");
}
