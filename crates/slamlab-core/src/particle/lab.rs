//! The resampling lab's pieces: preset weight sets, the weight editor's input
//! check, and copy-count statistics (thesis `000` Sec. 2.3). The `slamlab
//! experiment resampling` command and the lab window use the same ones.
//!
//! A resampler gives particle `i` a random number of copies `cᵢ` with
//! `E[cᵢ] = M wᵢ` (unbiased); what tells them apart is `Var[cᵢ]`, the noise that
//! resampling adds. Multinomial has the binomial `M wᵢ (1 − wᵢ)`; low-variance
//! (systematic) gives `⌊M wᵢ⌋` or `⌈M wᵢ⌉`, so its variance is at most ¼.

use super::resample::{Resampler, resample_indices};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// The most particles the lab holds (its per-particle histograms grow as `M²`).
pub const MAX_LAB_PARTICLES: usize = 200;

/// The most resamplings one [`ResamplingLab::resample`] call runs.
pub const MAX_PRESSES: usize = 100_000;

/// A preset set of weights for the lab.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum WeightPreset {
    /// One particle (the middle one) holds 0.8; the others share 0.2 equally.
    OneDominant,
    /// Every particle has weight `1/M`.
    Uniform,
    /// Two Gaussian bumps (standard deviation `M/12` particles) at a quarter and
    /// three quarters of the row, the second half as high.
    TwoModes,
    /// Every eighth particle has weight proportional to 1, the rest 1/100: most
    /// particles expect far less than one copy.
    ManyTiny,
}

impl WeightPreset {
    /// Every preset, in the lab's order.
    pub const ALL: [WeightPreset; 4] = [
        WeightPreset::OneDominant,
        WeightPreset::Uniform,
        WeightPreset::TwoModes,
        WeightPreset::ManyTiny,
    ];

    /// The name used in URLs, the CLI and JSON.
    pub fn name(self) -> &'static str {
        match self {
            WeightPreset::OneDominant => "one-dominant",
            WeightPreset::Uniform => "uniform",
            WeightPreset::TwoModes => "two-modes",
            WeightPreset::ManyTiny => "many-tiny",
        }
    }

    /// Parses a name as written by [`WeightPreset::name`].
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|p| p.name() == name)
    }

    /// The normalized weights of `m` particles (`m = 0` is treated as 1).
    pub fn weights(self, m: usize) -> Vec<f64> {
        let m = m.max(1);
        let raw: Vec<f64> = match self {
            WeightPreset::OneDominant if m == 1 => vec![1.0],
            WeightPreset::OneDominant => (0..m)
                .map(|i| {
                    if i == m / 2 {
                        0.8
                    } else {
                        0.2 / (m - 1) as f64
                    }
                })
                .collect(),
            WeightPreset::Uniform => vec![1.0; m],
            WeightPreset::TwoModes => {
                let sigma = (m as f64 / 12.0).max(0.5);
                let bump = |i: usize, centre: f64| {
                    let d = (i as f64 - centre) / sigma;
                    crate::math::exp(-0.5 * d * d)
                };
                (0..m)
                    .map(|i| bump(i, 0.25 * (m - 1) as f64) + 0.5 * bump(i, 0.75 * (m - 1) as f64))
                    .collect()
            }
            WeightPreset::ManyTiny => (0..m)
                .map(|i| if i % 8 == 0 { 1.0 } else { 0.01 })
                .collect(),
        };
        let total: f64 = raw.iter().sum();
        raw.into_iter().map(|w| w / total).collect()
    }
}

/// Weights from the lab's editor after the check.
#[derive(Clone, Debug, PartialEq)]
pub struct SanitizedWeights {
    /// Normalized weights (non-negative, summing to 1, at least one particle).
    pub weights: Vec<f64>,
    /// What was changed and why, for the lab to show; `None` when the input was fine.
    pub note: Option<String>,
}

/// Checks weights typed into the lab's editor: negative, NaN and infinite entries
/// become 0; all-zero (or empty) input becomes uniform; the rest is normalized.
/// Every change is described in the note.
pub fn sanitize_weights(input: &[f64]) -> SanitizedWeights {
    if input.is_empty() {
        return SanitizedWeights {
            weights: vec![1.0],
            note: Some("there were no weights; the lab uses one particle of weight 1".to_owned()),
        };
    }
    let mut notes = Vec::new();
    let bad: Vec<usize> = input
        .iter()
        .enumerate()
        .filter(|(_, w)| !(w.is_finite() && **w >= 0.0))
        .map(|(i, _)| i)
        .collect();
    if !bad.is_empty() {
        notes.push(format!(
            "{} weight(s) were negative, NaN or infinite (particle {}{}); they count as 0",
            bad.len(),
            bad[0],
            if bad.len() > 1 { " and others" } else { "" }
        ));
    }
    let clean: Vec<f64> = input
        .iter()
        .map(|&w| if w.is_finite() && w >= 0.0 { w } else { 0.0 })
        .collect();
    let total: f64 = clean.iter().sum();
    let weights = if total > 0.0 && total.is_finite() {
        clean.iter().map(|w| w / total).collect()
    } else {
        notes.push("every weight is zero; the lab uses uniform weights".to_owned());
        vec![1.0 / clean.len() as f64; clean.len()]
    };
    SanitizedWeights {
        weights,
        note: (!notes.is_empty()).then(|| notes.join("; ")),
    }
}

/// How many copies each of `n` particles got from resampled `indices`
/// (indices `≥ n` are ignored).
pub fn copy_counts(indices: &[usize], n: usize) -> Vec<usize> {
    let mut counts = vec![0; n];
    for &i in indices {
        if let Some(c) = counts.get_mut(i) {
            *c += 1;
        }
    }
    counts
}

/// Running mean and variance of every particle's copy count over repeated
/// resamplings.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CopyCountStats {
    trials: u64,
    sum: Vec<f64>,
    sum_sq: Vec<f64>,
}

impl CopyCountStats {
    /// Empty statistics for `n` particles.
    pub fn new(n: usize) -> Self {
        Self {
            trials: 0,
            sum: vec![0.0; n],
            sum_sq: vec![0.0; n],
        }
    }

    /// Adds one resampling's copy counts (extra entries are ignored).
    pub fn add(&mut self, counts: &[usize]) {
        self.trials += 1;
        for ((s, q), &c) in self.sum.iter_mut().zip(&mut self.sum_sq).zip(counts) {
            let c = c as f64;
            *s += c;
            *q += c * c;
        }
    }

    /// Number of resamplings added.
    pub fn trials(&self) -> u64 {
        self.trials
    }

    /// Mean copies of each particle.
    pub fn means(&self) -> Vec<f64> {
        let t = self.trials.max(1) as f64;
        self.sum.iter().map(|s| s / t).collect()
    }

    /// Variance of each particle's copy count (population variance over trials).
    pub fn variances(&self) -> Vec<f64> {
        let t = self.trials.max(1) as f64;
        self.sum
            .iter()
            .zip(&self.sum_sq)
            .map(|(s, q)| {
                let mean = s / t;
                (q / t - mean * mean).max(0.0)
            })
            .collect()
    }

    /// The variance of the copy counts averaged over particles.
    pub fn mean_variance(&self) -> f64 {
        let v = self.variances();
        v.iter().sum::<f64>() / v.len().max(1) as f64
    }

    /// The largest `|mean copies − M wᵢ|` over particles: 0 for an unbiased
    /// resampler, up to sampling error.
    pub fn max_bias(&self, weights: &[f64]) -> f64 {
        let m: f64 = self.sum.iter().sum::<f64>() / self.trials.max(1) as f64;
        self.means()
            .iter()
            .zip(weights)
            .map(|(mean, w)| (mean - m * w).abs())
            .fold(0.0, f64::max)
    }
}

/// One method's record in the lab.
#[derive(Clone, Debug, PartialEq)]
struct MethodRecord {
    method: Resampler,
    last: Vec<usize>,
    stats: CopyCountStats,
    /// `histograms[i][c]`: how often particle `i` got `c` copies.
    histograms: Vec<Vec<u64>>,
}

/// The resampling lab's state (`lesson=resampling`): one weighted particle row,
/// and for every method the copy counts of its latest resampling, the running
/// mean and variance of each particle's copies, and each particle's histogram of
/// copy counts. It owns its random generator, so a seed replays the same presses.
#[derive(Clone, Debug)]
pub struct ResamplingLab {
    weights: Vec<f64>,
    note: Option<String>,
    rng: ChaCha8Rng,
    records: Vec<MethodRecord>,
    indices: Vec<usize>,
}

impl ResamplingLab {
    /// A lab on `weights` (checked with [`sanitize_weights`]; more than
    /// [`MAX_LAB_PARTICLES`] are cut, with a note).
    pub fn new(weights: &[f64], seed: u64) -> Self {
        let mut lab = Self {
            weights: Vec::new(),
            note: None,
            rng: ChaCha8Rng::seed_from_u64(seed),
            records: Vec::new(),
            indices: Vec::new(),
        };
        lab.set_weights(weights);
        lab
    }

    /// A lab on a preset with `m` particles (clamped to `1..=MAX_LAB_PARTICLES`).
    pub fn from_preset(preset: WeightPreset, m: usize, seed: u64) -> Self {
        Self::new(&preset.weights(m.clamp(1, MAX_LAB_PARTICLES)), seed)
    }

    /// Replaces the weights (as typed into the editor) and clears every record.
    /// Returns the note about what had to be changed, if anything.
    pub fn set_weights(&mut self, weights: &[f64]) -> Option<&str> {
        let cut = weights.len() > MAX_LAB_PARTICLES;
        let mut checked = sanitize_weights(&weights[..weights.len().min(MAX_LAB_PARTICLES)]);
        if cut {
            let msg = format!(
                "the lab holds at most {MAX_LAB_PARTICLES} particles; the other {} were left out",
                weights.len() - MAX_LAB_PARTICLES
            );
            checked.note = Some(match checked.note {
                Some(n) => format!("{msg}; {n}"),
                None => msg,
            });
        }
        let m = checked.weights.len();
        self.weights = checked.weights;
        self.note = checked.note;
        self.records = Resampler::ALL
            .into_iter()
            .map(|method| MethodRecord {
                method,
                last: Vec::new(),
                stats: CopyCountStats::new(m),
                histograms: vec![vec![0; m + 1]; m],
            })
            .collect();
        self.note.as_deref()
    }

    /// The normalized weights.
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// What the weight check changed, if anything.
    pub fn note(&self) -> Option<&str> {
        self.note.as_deref()
    }

    /// `M wᵢ`: the copies each particle gets on average from any unbiased method.
    pub fn expected_copies(&self) -> Vec<f64> {
        let m = self.weights.len() as f64;
        self.weights.iter().map(|w| m * w).collect()
    }

    fn record(&self, method: Resampler) -> Option<&MethodRecord> {
        self.records.iter().find(|r| r.method == method)
    }

    /// Resamples `times` times (at most [`MAX_PRESSES`]) with `method`, drawing
    /// `M` particles each time.
    pub fn resample(&mut self, method: Resampler, times: usize) {
        let m = self.weights.len();
        let Some(record) = self.records.iter_mut().find(|r| r.method == method) else {
            return;
        };
        for _ in 0..times.min(MAX_PRESSES) {
            resample_indices(method, &self.weights, m, &mut self.rng, &mut self.indices);
            let counts = copy_counts(&self.indices, m);
            record.stats.add(&counts);
            for (h, &c) in record.histograms.iter_mut().zip(&counts) {
                if let Some(slot) = h.get_mut(c) {
                    *slot += 1;
                }
            }
            record.last = counts;
        }
    }

    /// The copy counts of `method`'s latest resampling (empty before the first).
    pub fn last_copies(&self, method: Resampler) -> &[usize] {
        self.record(method).map_or(&[], |r| &r.last)
    }

    /// `method`'s running copy-count statistics.
    pub fn stats(&self, method: Resampler) -> Option<&CopyCountStats> {
        self.record(method).map(|r| &r.stats)
    }

    /// How often particle `particle` got 0, 1, …, M copies under `method`.
    pub fn histogram(&self, method: Resampler, particle: usize) -> &[u64] {
        self.record(method)
            .and_then(|r| r.histograms.get(particle))
            .map_or(&[], |h| h.as_slice())
    }
}

/// The copy-count variance of multinomial resampling averaged over particles,
/// `(1/N) Σ M wᵢ (1 − wᵢ)` (binomial counts), for comparison with measurements.
pub fn multinomial_variance(weights: &[f64], m: usize) -> f64 {
    let m = m as f64;
    weights.iter().map(|w| m * w * (1.0 - w)).sum::<f64>() / weights.len().max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_are_normalized_and_shaped_as_named() {
        for p in WeightPreset::ALL {
            for m in [1, 2, 10, 20, 64] {
                let w = p.weights(m);
                assert_eq!(w.len(), m);
                assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12, "{p:?} {m}");
                assert!(w.iter().all(|w| *w > 0.0));
            }
            assert_eq!(WeightPreset::from_name(p.name()), Some(p));
        }
        let w = WeightPreset::OneDominant.weights(20);
        assert!((w[10] - 0.8).abs() < 1e-12);
        let w = WeightPreset::ManyTiny.weights(20);
        // Three heavy particles (0, 8, 16) and 17 light ones: M w = 20 × 0.01/3.17.
        assert!((w[1] * 20.0 - 0.2 / 3.17).abs() < 1e-12);
        let w = WeightPreset::TwoModes.weights(20);
        let peak = w.iter().cloned().fold(0.0, f64::max);
        assert!(w[5] == peak || w[4] == peak, "{w:?}");
    }

    #[test]
    fn the_editor_check_replaces_bad_weights() {
        let s = sanitize_weights(&[1.0, -2.0, f64::NAN, 3.0]);
        assert_eq!(s.weights, vec![0.25, 0.0, 0.0, 0.75]);
        assert!(
            s.note
                .as_deref()
                .is_some_and(|n| n.contains("particle 1 and others"))
        );
        let s = sanitize_weights(&[0.0, 0.0]);
        assert_eq!(s.weights, vec![0.5, 0.5]);
        assert!(s.note.as_deref().is_some_and(|n| n.contains("uniform")));
        let s = sanitize_weights(&[-1.0, f64::INFINITY]);
        assert_eq!(s.weights, vec![0.5, 0.5]);
        assert_eq!(sanitize_weights(&[]).weights, vec![1.0]);
        assert_eq!(sanitize_weights(&[2.0, 2.0]).note, None);
    }

    /// Issue 13's resampler tests on the lab's presets: every method unbiased;
    /// low-variance and stratified below multinomial's variance; residual at least
    /// `⌊M w⌋` copies.
    #[test]
    fn resamplers_on_the_presets() {
        let m = 20;
        let trials = 4000;
        let mut rng = ChaCha8Rng::seed_from_u64(13);
        let mut idx = Vec::new();
        for preset in WeightPreset::ALL {
            let w = preset.weights(m);
            let mut variance = Vec::new();
            for method in Resampler::ALL {
                let mut stats = CopyCountStats::new(m);
                for _ in 0..trials {
                    resample_indices(method, &w, m, &mut rng, &mut idx);
                    let c = copy_counts(&idx, m);
                    assert_eq!(c.iter().sum::<usize>(), m);
                    if method == Resampler::Residual {
                        for (ci, wi) in c.iter().zip(&w) {
                            assert!(*ci as f64 >= (m as f64 * wi).floor(), "{preset:?}");
                        }
                    }
                    stats.add(&c);
                }
                // The standard error of a mean count is at most sqrt(M w (1 − w) / trials)
                // ≤ sqrt(5 / 4000) = 0.035 here; 0.15 is over four of them.
                let bias = stats.max_bias(&w);
                assert!(bias < 0.15, "{preset:?} {method:?}: bias {bias}");
                variance.push(stats.mean_variance());
            }
            let [multinomial, low_variance, stratified, residual] = variance[..] else {
                unreachable!()
            };
            let theory = multinomial_variance(&w, m);
            assert!(
                (multinomial - theory).abs() < 0.1 * theory,
                "{preset:?}: {multinomial} vs {theory}"
            );
            assert!(low_variance < 0.7 * multinomial, "{preset:?} {variance:?}");
            assert!(stratified < multinomial, "{preset:?} {variance:?}");
            assert!(residual <= multinomial, "{preset:?} {variance:?}");
            // Systematic counts are ⌊M w⌋ or ⌈M w⌉: variance at most ¼.
            assert!(low_variance <= 0.25 + 1e-9, "{preset:?} {variance:?}");
            if preset == WeightPreset::Uniform {
                // M w = 1 exactly: low-variance and residual are deterministic.
                assert!(low_variance < 1e-12 && residual < 1e-12, "{variance:?}");
            }
        }
    }

    #[test]
    fn the_lab_records_presses_per_method() {
        let mut lab = ResamplingLab::from_preset(WeightPreset::OneDominant, 10, 1);
        assert_eq!(lab.weights().len(), 10);
        assert!(lab.last_copies(Resampler::Multinomial).is_empty());
        lab.resample(Resampler::LowVariance, 1000);
        lab.resample(Resampler::Multinomial, 1);
        assert_eq!(lab.stats(Resampler::LowVariance).unwrap().trials(), 1000);
        assert_eq!(lab.stats(Resampler::Multinomial).unwrap().trials(), 1);
        assert_eq!(lab.stats(Resampler::Stratified).unwrap().trials(), 0);
        // The dominant particle (M w = 8) gets exactly 8 copies from low-variance.
        let h = lab.histogram(Resampler::LowVariance, 5);
        assert_eq!(h[8], 1000);
        assert_eq!(lab.last_copies(Resampler::LowVariance)[5], 8);
        assert_eq!(
            lab.last_copies(Resampler::Multinomial)
                .iter()
                .sum::<usize>(),
            10
        );
        assert!((lab.expected_copies()[5] - 8.0).abs() < 1e-12);
        // Bad editor input: a note and a safe row; the records start over.
        let note = lab.set_weights(&[f64::NAN, -1.0, 0.0]).map(str::to_owned);
        assert!(note.is_some_and(|n| n.contains("uniform")));
        assert_eq!(lab.weights(), &[1.0 / 3.0; 3]);
        assert_eq!(lab.stats(Resampler::LowVariance).unwrap().trials(), 0);
        let big = vec![1.0; MAX_LAB_PARTICLES + 5];
        assert!(
            lab.set_weights(&big)
                .is_some_and(|n| n.contains("left out"))
        );
        assert_eq!(lab.weights().len(), MAX_LAB_PARTICLES);
        // The same seed replays the same presses.
        let mut a = ResamplingLab::from_preset(WeightPreset::TwoModes, 20, 7);
        let mut b = ResamplingLab::from_preset(WeightPreset::TwoModes, 20, 7);
        a.resample(Resampler::Stratified, 5);
        b.resample(Resampler::Stratified, 5);
        assert_eq!(
            a.last_copies(Resampler::Stratified),
            b.last_copies(Resampler::Stratified)
        );
    }

    #[test]
    fn copy_counts_ignore_out_of_range_indices() {
        assert_eq!(copy_counts(&[0, 0, 2, 7], 3), vec![2, 0, 1]);
        let mut s = CopyCountStats::new(2);
        s.add(&[2, 0]);
        s.add(&[0, 2]);
        assert_eq!(s.means(), vec![1.0, 1.0]);
        assert_eq!(s.variances(), vec![1.0, 1.0]);
        assert_eq!(s.trials(), 2);
    }
}
