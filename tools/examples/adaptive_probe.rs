use crane_tools::{cases::Case, reference, workprec};
fn main() {
    for case in Case::all() {
        let refr = reference::reference(&case, 1e-3, 100).unwrap();
        let o = workprec::Options::default();
        let pts = workprec::sweep(&case, &refr, &o, |m| eprintln!("{m}")).unwrap();
        for p in &pts {
            println!(
                "{:<60} {:>10.3e} s  rmse {:.3e} steps {}",
                workprec::setting_name(p),
                p.time_s,
                p.rmse,
                p.steps
            );
        }
        let lv = workprec::compare(&pts);
        println!("{}", workprec::table(case.name, &lv));
        let _ = std::fs::create_dir_all("out");
        workprec::diagram(
            std::path::Path::new(&format!("out/wp_{}.svg", case.name.replace(' ', ""))),
            case.name,
            &pts,
            &lv,
        )
        .unwrap();
    }
}
