//! The filters lesson's one-step comparison, which the app recomputes on every
//! drag of the prior: 100,000 samples (and 200 particles) through the chosen
//! function, the EKF's linearization and the unscented transform.
//! `cargo bench -p slamlab-sim --bench filters`.
//!
//! Target (docs/filters.md, "Speed"): well under a 16 ms frame natively, so the
//! browser (about 1.5-2x slower) stays interactive while dragging.

use slamlab_sim::filters_lab::{FUNCTION_NAMES, FiltersScenario, FunctionKind, one_step};

fn main() {
    divan::main();
}

fn scenario(name: &str) -> FiltersScenario {
    let i = FUNCTION_NAMES.iter().position(|n| *n == name).unwrap_or(0);
    let function = FunctionKind::ALL[i];
    let (mean, std, rho) = function.default_prior();
    FiltersScenario {
        function,
        mean,
        std,
        rho,
        ..Default::default()
    }
}

#[divan::bench(args = ["polar", "range-bearing", "motion"])]
fn one_step_100k_samples(bencher: divan::Bencher, function: &str) {
    let s = scenario(function);
    bencher.bench(|| one_step(divan::black_box(&s)).map(|r| r.rows.len()));
}
