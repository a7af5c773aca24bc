//! The filters lesson's one-step comparison, which the app recomputes on every
//! drag of the prior: 100,000 samples (and 200 particles) through the chosen
//! function, the EKF's linearization and the unscented transform.
//! `cargo bench -p slamlab-sim --bench filters`.
//!
//! `one_step_kept_draws` is what a drag costs: the lesson keeps the standard
//! normal draws ([`Draws`]) and only moves them to the new prior.
//!
//! Target (docs/filters.md, "Speed"): well under a 16 ms frame natively, so the
//! browser (about 1.5-2x slower) stays interactive while dragging.

use slamlab_core::filters::one_step;
use slamlab_sim::filters::session::{
    Draws, FUNCTION_NAMES, FiltersScenario, FunctionKind, one_step, one_step_with,
};

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

#[divan::bench(args = ["polar", "range-bearing", "motion"])]
fn one_step_kept_draws(bencher: divan::Bencher, function: &str) {
    let s = scenario(function);
    let mut draws = Draws::default();
    let _ = one_step_with(&s, &mut draws);
    bencher.bench_local(|| one_step_with(divan::black_box(&s), &mut draws).map(|r| r.rows.len()));
}

/// Where a recomputation's time goes: the draws the lesson keeps between drags
/// (100,000 samples' and 200 particles' standard normal pairs) ...
#[divan::bench]
fn draws_only(bencher: divan::Bencher) {
    use rand::SeedableRng;
    bencher.bench(|| {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(divan::black_box(1));
        one_step::standard_normals(100_200, &mut rng).len()
    });
}

/// ... the samples moved to the prior and pushed through the function ...
#[divan::bench(args = ["polar", "range-bearing", "motion"])]
fn samples_from_kept_draws(bencher: divan::Bencher, function: &str) {
    use rand::SeedableRng;
    let s = scenario(function);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let normals = one_step::standard_normals(100_000, &mut rng);
    let (prior, f) = (s.prior(), s.step_function());
    bencher.bench(|| {
        one_step::sample_from_normals(&prior, &f, divan::black_box(&normals), "samples")
            .map(|c| c.points.len())
    });
}

/// ... and their moments alone.
#[divan::bench]
fn moments_only(bencher: divan::Bencher) {
    use rand::SeedableRng;
    let s = scenario("polar");
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let normals = one_step::standard_normals(100_000, &mut rng);
    let Ok(cloud) =
        one_step::sample_from_normals(&s.prior(), &s.step_function(), &normals, "samples")
    else {
        return;
    };
    bencher.bench(|| one_step::moments(divan::black_box(&cloud.points)).map(|g| g.mean[0]));
}
