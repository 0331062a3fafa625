//! Linker arguments of the firmware: `-Tdefmt.x` (defmt's symbol table) only with the `probe`
//! feature; `-Tlink.x` (cortex-m-rt) comes from `.cargo/config.toml` for the target.
fn main() {
    if std::env::var_os("CARGO_FEATURE_PROBE").is_some() {
        println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
    }
    println!("cargo:rerun-if-changed=build.rs");
}
