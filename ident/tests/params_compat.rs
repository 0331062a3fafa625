//! Parameter files written before `ParamsFile` became `crane_model::Params` (serde derives)
//! still load, with the same values, and a loaded file writes back unchanged.

use crane_ident::params_file::{parse, read, to_toml};
use std::path::Path;

#[test]
fn a_file_written_by_the_old_params_file_loads() {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/params_before_serde.toml");
    let p = read(&path).expect("old file loads");
    assert_eq!(p.payload_mass, 0.064);
    assert_eq!(p.trolley_mass, 1.155);
    assert_eq!(p.x.gain, 3.198720145495128);
    assert_eq!(p.x.dry_pos[4], 10.972728559981755);
    let again = parse(Path::new("again.toml"), &to_toml(&p)).expect("round trip");
    assert_eq!(p, again);
    let old = std::fs::read_to_string(&path).unwrap();
    assert_eq!(to_toml(&p), old, "the format changed");
}
