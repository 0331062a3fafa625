//! `crane demo` / `crane identify`: one friction figure per drive axis (both directions),
//! each a well-formed SVG with the estimate, its bands, the probes and, when the data set
//! comes from the virtual rig, the truth.

use std::path::Path;
use std::process::Command;

mod support;
use support::tmp;

fn crane(args: &[&str], paths: &[&Path]) {
    let mut c = Command::new(env!("CARGO_BIN_EXE_crane"));
    c.args(args);
    for p in paths {
        c.arg(p);
    }
    let out = c.output().expect("run crane");
    assert!(
        out.status.success(),
        "crane {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Texts, number of `<circle>` and of `<polygon>` elements of an SVG file.
fn svg_parts(path: &Path) -> (String, usize, usize) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let doc = roxmltree::Document::parse(&text).expect("well-formed SVG (XML)");
    assert_eq!(doc.root_element().tag_name().name(), "svg");
    let count = |tag: &str| {
        doc.descendants()
            .filter(|n| n.tag_name().name() == tag)
            .count()
    };
    let texts = doc
        .descendants()
        .filter(|n| n.is_text())
        .filter_map(|n| n.text())
        .collect::<Vec<_>>()
        .join("|");
    (texts, count("circle"), count("polygon"))
}

#[test]
fn demo_and_identify_write_friction_figures_with_bands() {
    let dir = tmp("demo");
    crane(&["demo", "--out"], &[&dir]);
    let plots = dir.join("plots");
    for axis in ["x", "y"] {
        let (texts, circles, polygons) = svg_parts(&plots.join(format!("friction_{axis}.svg")));
        for want in [
            "Cbar+",
            "Cbar-",
            "95 % band over the axis (simultaneous)",
            "pointwise 95 % band",
            "breakaway probes",
            "truth (virtual rig)",
        ] {
            assert!(texts.contains(want), "{axis}: no `{want}` in {texts}");
        }
        // one band per direction; the probes of both directions (at most 15 each) plus
        // their legend marks
        assert_eq!(polygons, 2, "{axis}");
        assert!((2 + 2..=2 * 15 + 2).contains(&circles), "{axis}: {circles}");
    }
    // a data set without the rig's truth file: the same figures, without a truth curve
    let ds = dir.join("dataset");
    std::fs::remove_file(ds.join("truth_params.toml")).expect("rig wrote its truth");
    let plots2 = dir.join("plots2");
    crane(
        &["identify", "--out"],
        &[&dir.join("p2.toml"), Path::new("--plots"), &plots2, &ds],
    );
    let (texts, _, polygons) = svg_parts(&plots2.join("friction_x.svg"));
    assert!(!texts.contains("truth"), "{texts}");
    assert_eq!(polygons, 2);
    let _ = std::fs::remove_dir_all(&dir);
}
