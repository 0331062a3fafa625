//! The identification issue's speed target: the whole campaign on the virtual rig (every
//! experiment simulated and its CSV written) plus the identification of the data set, under
//! 10 s. Measured here, not in a timed unit test (`ident/tests/identification.rs` checks the
//! numbers, this the time):
//!
//! ```sh
//! cargo bench -p crane-ident --bench campaign
//! ```

use crane_ident::campaign::{run_campaign, Campaign};
use crane_ident::data::{load_dataset, Constants};
use crane_ident::identify::identify_dataset;
use crane_ident::rig::{PlantConfig, VirtualRig};
use crane_model::Params;
use criterion::{criterion_group, criterion_main, Criterion};
use std::time::Duration;

fn bench(c: &mut Criterion) {
    let dir = std::env::temp_dir().join(format!("crane-ident-bench-{}", std::process::id()));
    let mut g = c.benchmark_group("identification");
    g.sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(30));
    g.bench_function("campaign_write_load_identify", |b| {
        b.iter(|| {
            let _ = std::fs::remove_dir_all(&dir);
            let mut rig = VirtualRig::new(Params::default(), PlantConfig::default());
            let camp = Campaign::default();
            run_campaign(&mut rig, &camp, &Constants::default(), Some(&dir)).expect("campaign");
            let ds = load_dataset(&dir).expect("load");
            identify_dataset(&ds, &camp.ident).expect("identify")
        })
    });
    g.finish();
    let _ = std::fs::remove_dir_all(&dir);
}

criterion_group!(benches, bench);
criterion_main!(benches);
