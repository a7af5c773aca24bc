//! The resampling experiment behind `slamlab experiment resampling`: every
//! resampler (thesis `000` Sec. 2.3, Algorithms 6 and 7, plus stratified and
//! residual) run many times on the lab's preset weight sets
//! ([`WeightPreset`]), measuring the mean and variance of each particle's copy
//! count. An unbiased method's mean copies are `M wᵢ`; the lower the variance,
//! the less noise resampling adds.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use slamlab_core::particle::lab::multinomial_variance;
use slamlab_core::particle::{
    CopyCountStats, Resampler, WeightPreset, copy_counts, resample_indices,
};

/// Particles per preset unless told otherwise (the lab's default row).
pub const DEFAULT_PARTICLES: usize = 20;

/// One method on one preset.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PresetResult {
    /// The preset's name.
    pub preset: String,
    /// Copy-count variance, averaged over particles.
    pub copy_count_variance: f64,
    /// The largest `|mean copies − M wᵢ|` over particles (0 up to sampling error
    /// for an unbiased method).
    pub max_bias: f64,
}

/// One method's results.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MethodResult {
    /// The method's name.
    pub method: String,
    /// One entry per preset.
    pub presets: Vec<PresetResult>,
}

/// The outcome of `slamlab experiment resampling`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ResamplingExperiment {
    /// "resampling".
    pub experiment: String,
    /// Particles per set (`M`, and the number drawn).
    pub particles: usize,
    /// Resamplings per method and preset.
    pub trials: usize,
    /// Seed of the generator (one ChaCha8 stream per method and preset).
    pub seed: u64,
    /// The preset weights used.
    pub weights: Vec<(String, Vec<f64>)>,
    /// Multinomial's theoretical variance `(1/M) Σ M wᵢ (1 − wᵢ)` per preset.
    pub multinomial_theory: Vec<(String, f64)>,
    /// One entry per method.
    pub results: Vec<MethodResult>,
}

/// Runs `trials` resamplings of `particles` particles with every method in
/// `methods` on every preset. `progress(done, total)` is called after each
/// method-preset pair.
pub fn resampling_experiment(
    methods: &[Resampler],
    particles: usize,
    trials: usize,
    seed: u64,
    mut progress: impl FnMut(usize, usize),
) -> ResamplingExperiment {
    let m = particles.max(1);
    let total = methods.len() * WeightPreset::ALL.len();
    let mut idx = Vec::with_capacity(m);
    let mut results = Vec::new();
    for (k, &method) in methods.iter().enumerate() {
        let mut presets = Vec::new();
        for (p, preset) in WeightPreset::ALL.into_iter().enumerate() {
            let weights = preset.weights(m);
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            rng.set_stream((k * WeightPreset::ALL.len() + p) as u64);
            let mut stats = CopyCountStats::new(m);
            for _ in 0..trials {
                resample_indices(method, &weights, m, &mut rng, &mut idx);
                stats.add(&copy_counts(&idx, m));
            }
            presets.push(PresetResult {
                preset: preset.name().to_owned(),
                copy_count_variance: stats.mean_variance(),
                max_bias: stats.max_bias(&weights),
            });
            progress(k * WeightPreset::ALL.len() + p + 1, total);
        }
        results.push(MethodResult {
            method: method.name().to_owned(),
            presets,
        });
    }
    ResamplingExperiment {
        experiment: "resampling".to_owned(),
        particles: m,
        trials,
        seed,
        weights: WeightPreset::ALL
            .into_iter()
            .map(|p| (p.name().to_owned(), p.weights(m)))
            .collect(),
        multinomial_theory: WeightPreset::ALL
            .into_iter()
            .map(|p| (p.name().to_owned(), multinomial_variance(&p.weights(m), m)))
            .collect(),
        results,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_experiment_orders_the_methods_as_theory_says() {
        let e = resampling_experiment(&Resampler::ALL, 20, 2000, 1, |_, _| {});
        assert_eq!(e.results.len(), 4);
        for (p, (name, theory)) in e.multinomial_theory.iter().enumerate() {
            let var = |m: usize| e.results[m].presets[p].copy_count_variance;
            assert_eq!(&e.results[0].presets[p].preset, name);
            // 2000 trials: the variance estimate is within about 10 % of theory.
            assert!(
                (var(0) - theory).abs() < 0.12 * theory,
                "{name}: {} vs {theory}",
                var(0)
            );
            assert!(
                var(1) < var(0) && var(2) < var(0) && var(3) <= var(0),
                "{name}"
            );
            for r in &e.results {
                assert!(r.presets[p].max_bias < 0.2, "{} {name}", r.method);
            }
        }
    }
}
