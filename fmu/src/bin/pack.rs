//! `crane-fmu-pack --lib PATH/libcrane_fmu.so --out crane.fmu`: writes the FMU archive
//! (`modelDescription.xml`, `binaries/linux64/crane.so`, `documentation/index.html`),
//! atomically (a temporary file beside `--out`, then a rename). `scripts/build-fmu.sh` builds
//! the library and calls this.

use crane_fmu::description::{documentation, model_description, MODEL_IDENTIFIER};
use std::io::Write;
use std::path::{Path, PathBuf};

fn usage() -> String {
    "usage: crane-fmu-pack --lib PATH/libcrane_fmu.so --out crane.fmu".into()
}

fn args() -> Result<(PathBuf, PathBuf), String> {
    let mut lib = None;
    let mut out = None;
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        match a.as_str() {
            "--lib" => lib = it.next().map(PathBuf::from),
            "--out" => out = it.next().map(PathBuf::from),
            "-h" | "--help" => return Err(usage()),
            other => return Err(format!("unknown argument {other:?}\n{}", usage())),
        }
    }
    match (lib, out) {
        (Some(l), Some(o)) => Ok((l, o)),
        _ => Err(usage()),
    }
}

fn pack(lib: &Path, out: &Path) -> Result<(), String> {
    let so = std::fs::read(lib).map_err(|e| format!("read {}: {e}", lib.display()))?;
    if so.get(..4) != Some(b"\x7fELF") {
        return Err(format!("{}: not an ELF shared library", lib.display()));
    }
    let same = |a: &Path, b: &Path| match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    };
    if same(lib, out) {
        return Err(format!(
            "--out {} would replace the input --lib",
            out.display()
        ));
    }
    if out.exists() && out.is_dir() {
        return Err(format!("{}: is a directory", out.display()));
    }
    let tmp = out.with_extension("fmu.tmp");
    let write = || -> Result<(), Box<dyn std::error::Error>> {
        let file = std::fs::File::create(&tmp)?;
        let mut zip = zip::ZipWriter::new(file);
        let opts = zip::write::SimpleFileOptions::default()
            .compression_method(zip::CompressionMethod::Deflated)
            .unix_permissions(0o644);
        zip.start_file("modelDescription.xml", opts)?;
        zip.write_all(model_description().as_bytes())?;
        zip.start_file(
            format!("binaries/linux64/{MODEL_IDENTIFIER}.so"),
            opts.unix_permissions(0o755),
        )?;
        zip.write_all(&so)?;
        zip.start_file("documentation/index.html", opts)?;
        zip.write_all(documentation().as_bytes())?;
        zip.finish()?.sync_all()?;
        Ok(())
    };
    if let Err(e) = write() {
        let _ = std::fs::remove_file(&tmp);
        return Err(format!("write {}: {e}", tmp.display()));
    }
    std::fs::rename(&tmp, out).map_err(|e| format!("rename to {}: {e}", out.display()))
}

fn main() {
    let r = args().and_then(|(lib, out)| {
        pack(&lib, &out)?;
        println!("crane-fmu-pack: {}", out.display());
        Ok(())
    });
    if let Err(e) = r {
        eprintln!("crane-fmu-pack: {e}");
        std::process::exit(2);
    }
}
