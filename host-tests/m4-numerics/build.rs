//! The firmware's memory map (QEMU mps2-an386) on the linker's search path; `-Tlink.x` comes
//! from the repository's `.cargo/config.toml` for the target.
use std::path::PathBuf;

fn main() {
    let out = PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    std::fs::copy("../../firmware/memory.x", out.join("memory.x")).expect("copy memory.x");
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed=../../firmware/memory.x");
    println!("cargo:rerun-if-changed=build.rs");
}
