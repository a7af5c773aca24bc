//! The resampling lab (`lesson=resampling`): one row of weighted particles and
//! the four resamplers side by side (thesis `000` Sec. 2.3; slides `001`). The
//! student presses "resample" once or a thousand times and sees, per method, how
//! many copies each particle got and how much those counts scatter around
//! `M wᵢ`.
//!
//! [`LabScenario`] is the lesson's parameter table; [`LabRun`] is the lab with
//! the list of presses, so that a seed replays them and a step back is exact.

use crate::params::{self, Param, Scenario, count_field};
use serde::{Deserialize, Serialize};
use slamlab_core::particle::lab::{MAX_LAB_PARTICLES, MAX_PRESSES};
use slamlab_core::particle::{Resampler, ResamplingLab, WeightPreset};

/// Where the lab's weights come from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LabWeights {
    /// A preset with [`LabScenario::particles`] particles.
    Preset(WeightPreset),
    /// The weights as typed (unnormalized; checked when the lab opens).
    Custom(Vec<f64>),
}

/// The lab's parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct LabScenario {
    /// Seed of the lab's random generator.
    pub seed: u64,
    /// The weights.
    pub weights: LabWeights,
    /// Particles in a preset row (`M`; a typed list has its own length).
    pub particles: usize,
    /// The methods compared, in order.
    pub methods: Vec<Resampler>,
    /// Resamplings per press of "Resample ×N".
    pub presses: usize,
    /// The particle whose copy-count histogram the plots show; `None`: the heaviest.
    pub focus: Option<usize>,
}

impl Default for LabScenario {
    fn default() -> Self {
        Self {
            seed: 1,
            weights: LabWeights::Preset(WeightPreset::TwoModes),
            particles: 20,
            methods: Resampler::ALL.to_vec(),
            presses: 1000,
            focus: None,
        }
    }
}

const PRESET_NAMES: &[&str] = &["one-dominant", "uniform", "two-modes", "many-tiny"];
const METHOD_NAMES: &[&str] = &["multinomial", "low-variance", "stratified", "residual"];

/// Reads `weights=`: a preset's name or a comma-separated list of numbers.
fn parse_weights(value: &str) -> Result<LabWeights, String> {
    if let Some(preset) = WeightPreset::from_name(value) {
        return Ok(LabWeights::Preset(preset));
    }
    let expected = || {
        format!(
            "one of {}, or the weights themselves separated by commas (e.g. 5,1,1,3; at most {MAX_LAB_PARTICLES})",
            PRESET_NAMES.join(", ")
        )
    };
    let numbers: Result<Vec<f64>, _> = value.split(',').map(|t| t.trim().parse::<f64>()).collect();
    match numbers {
        Ok(list) if !list.is_empty() && list.len() <= MAX_LAB_PARTICLES => {
            Ok(LabWeights::Custom(list))
        }
        _ => Err(expected()),
    }
}

fn weights_text(weights: &LabWeights) -> String {
    match weights {
        LabWeights::Preset(p) => p.name().to_owned(),
        LabWeights::Custom(list) => list
            .iter()
            // Shortest text that reads back to the same number: a link keeps
            // even a tiny weight.
            .map(|w| w.to_string())
            .collect::<Vec<_>>()
            .join(","),
    }
}

/// The lab's parameter table.
pub static PARAMS: &[Param<LabScenario>] = &[
    count_field!(
        "seed",
        "seed of the lab's random generator (the same seed replays the same presses)",
        (0, u64::MAX),
        seed
    ),
    Param::words(
        "weights",
        "a preset weight set, or the weights themselves separated by commas (e.g. 5,1,1,3; normalized for you)",
        PRESET_NAMES,
        |s| Some(weights_text(&s.weights)),
        |s, v| parse_weights(v).map(|w| s.weights = w),
    ),
    Param::count(
        "particles",
        "",
        "particles in a preset row (M); a typed list has its own length",
        (1, MAX_LAB_PARTICLES as u64),
        |s| match s.weights {
            LabWeights::Preset(_) => Some(s.particles as u64),
            LabWeights::Custom(_) => None,
        },
        |s, v| s.particles = v as usize,
    ),
    Param::words(
        "methods",
        "the resamplers compared, comma separated",
        METHOD_NAMES,
        |s| Some(params::list_text(&s.methods, |m| m.name())),
        |s, v| params::choose_items(METHOD_NAMES, v, Resampler::from_name).map(|l| s.methods = l),
    ),
    count_field!(
        "presses",
        "resamplings per press of \"Resample ×N\"",
        (1, MAX_PRESSES as u64),
        presses
    ),
    Param::count(
        "focus",
        "",
        "the particle (0 = leftmost) whose copy-count histogram is plotted; default: the heaviest",
        (0, MAX_LAB_PARTICLES as u64 - 1),
        |s| s.focus.map(|f| f as u64),
        |s, v| s.focus = Some(v as usize),
    ),
];

impl Scenario for LabScenario {
    const LESSON: &'static str = "resampling";

    fn params() -> &'static [Param<Self>] {
        PARAMS
    }

    fn seed(&self) -> u64 {
        self.seed
    }
}

/// The lab with its history of presses.
#[derive(Clone, Debug)]
pub struct LabRun {
    scenario: LabScenario,
    lab: ResamplingLab,
    /// Resamplings per press, in order.
    presses: Vec<usize>,
}

impl LabRun {
    /// Opens the lab on `scenario` (the weights checked: negative, NaN and
    /// all-zero weights are repaired, with a note in [`LabRun::note`]).
    pub fn new(scenario: LabScenario) -> Self {
        let lab = Self::fresh_lab(&scenario);
        Self {
            scenario,
            lab,
            presses: Vec::new(),
        }
    }

    fn fresh_lab(scenario: &LabScenario) -> ResamplingLab {
        match &scenario.weights {
            LabWeights::Preset(p) => {
                ResamplingLab::from_preset(*p, scenario.particles, scenario.seed)
            }
            LabWeights::Custom(list) => ResamplingLab::new(list, scenario.seed),
        }
    }

    /// The scenario the lab runs.
    pub fn scenario(&self) -> &LabScenario {
        &self.scenario
    }

    /// The lab: weights, copy counts, statistics.
    pub fn lab(&self) -> &ResamplingLab {
        &self.lab
    }

    /// What the weight check had to repair, if anything.
    pub fn note(&self) -> Option<&str> {
        self.lab.note()
    }

    /// `M`: the particles in the row (and the number drawn by each resampling).
    pub fn particles(&self) -> usize {
        self.lab.weights().len()
    }

    /// Presses so far.
    pub fn press_count(&self) -> usize {
        self.presses.len()
    }

    /// Resamplings in the latest press, if any.
    pub fn last_press(&self) -> Option<usize> {
        self.presses.last().copied()
    }

    /// Resamplings per method so far.
    pub fn resamplings(&self) -> usize {
        self.presses.iter().sum()
    }

    /// The particle whose histogram is plotted: the chosen one if it exists, else
    /// the heaviest (the leftmost of equals).
    pub fn focus(&self) -> usize {
        let m = self.particles();
        match self.scenario.focus {
            Some(f) if f < m => f,
            _ => {
                let w = self.lab.weights();
                (0..m).fold(0, |best, i| if w[i] > w[best] { i } else { best })
            }
        }
    }

    /// Resamples `times` times (at most [`MAX_PRESSES`]) with every method, in
    /// the scenario's order.
    pub fn press(&mut self, times: usize) {
        let times = times.clamp(1, MAX_PRESSES);
        for &method in &self.scenario.methods {
            self.lab.resample(method, times);
        }
        self.presses.push(times);
    }

    /// Takes the latest press back (the lab is rebuilt from its seed and the
    /// earlier presses replayed, so the numbers are exactly those of before).
    /// Returns false when nothing was pressed yet.
    pub fn undo(&mut self) -> bool {
        if self.presses.pop().is_none() {
            return false;
        }
        let presses = std::mem::take(&mut self.presses);
        self.lab = Self::fresh_lab(&self.scenario);
        for times in presses {
            self.press(times);
        }
        true
    }

    /// Runs `scenario` from now on. The records stay when only what is shown
    /// changed (the presses per button, the plotted particle); new weights, a new
    /// seed or other methods start the lab over. Returns true when it started over.
    pub fn reconfigure(&mut self, scenario: LabScenario) -> bool {
        let same_lab = LabScenario {
            presses: self.scenario.presses,
            focus: self.scenario.focus,
            ..scenario.clone()
        } == self.scenario;
        if same_lab {
            self.scenario = scenario;
            false
        } else {
            *self = Self::new(scenario);
            true
        }
    }

    /// Sets the weights to `weights` as typed (the records start over).
    pub fn set_weights(&mut self, weights: Vec<f64>) {
        self.scenario.weights = LabWeights::Custom(weights);
        *self = Self::new(self.scenario.clone());
    }

    /// Chooses the particle whose histogram is plotted.
    pub fn set_focus(&mut self, particle: usize) {
        self.scenario.focus = Some(particle.min(MAX_LAB_PARTICLES - 1));
    }

    /// The copy-count variance of multinomial resampling for particle `i`,
    /// `M wᵢ (1 − wᵢ)` (binomial), to compare the measured ones with.
    pub fn multinomial_variance_of(&self, i: usize) -> f64 {
        let m = self.particles() as f64;
        self.lab.weights().get(i).map_or(0.0, |w| m * w * (1.0 - w))
    }

    /// The smallest copy-count variance any unbiased resampler can give particle
    /// `i`: that of taking `⌊M wᵢ⌋` or `⌈M wᵢ⌉` copies, `f (1 − f)` with `f` the
    /// fractional part of `M wᵢ`. Low-variance resampling reaches it.
    pub fn least_variance_of(&self, i: usize) -> f64 {
        let m = self.particles() as f64;
        self.lab.weights().get(i).map_or(0.0, |w| {
            let e = m * w;
            let f = e - e.floor();
            f * (1.0 - f)
        })
    }

    /// The probability that multinomial resampling gives particle `i` exactly `k`
    /// copies: Binomial(M, wᵢ) at `k`.
    pub fn binomial_pmf(&self, i: usize, k: usize) -> f64 {
        let m = self.particles();
        let Some(&w) = self.lab.weights().get(i) else {
            return 0.0;
        };
        if k > m {
            return 0.0;
        }
        // log C(M, k) + k log w + (M − k) log(1 − w), with 0 log 0 = 0.
        let log_choose: f64 = (0..k)
            .map(|j| {
                slamlab_core::math::ln((m - j) as f64) - slamlab_core::math::ln((j + 1) as f64)
            })
            .sum();
        let term = |count: usize, p: f64| {
            if count == 0 {
                0.0
            } else if p <= 0.0 {
                f64::NEG_INFINITY
            } else {
                count as f64 * slamlab_core::math::ln(p)
            }
        };
        slamlab_core::math::exp(log_choose + term(k, w) + term(m - k, 1.0 - w))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pairs_of(s: &LabScenario) -> Vec<(&'static str, String)> {
        params::to_pairs(s)
    }

    #[test]
    fn the_table_round_trips() {
        let mut s = LabScenario::default();
        for (k, v) in [
            ("seed", "7"),
            ("weights", "5,1,1,3"),
            ("methods", "residual,multinomial"),
            ("presses", "250"),
            ("focus", "2"),
        ] {
            assert_eq!(params::set(&mut s, k, v), None, "{k}={v}");
        }
        let pairs = pairs_of(&s);
        let mut back = LabScenario::default();
        let issues =
            params::apply_pairs(&mut back, pairs.iter().map(|(k, v)| (*k, v.as_str())), &[]);
        assert!(issues.is_empty(), "{issues:?}");
        assert_eq!(back, s);
        assert_eq!(s.weights, LabWeights::Custom(vec![5.0, 1.0, 1.0, 3.0]));
        assert_eq!(s.methods, vec![Resampler::Residual, Resampler::Multinomial]);
    }

    #[test]
    fn bad_values_say_what_was_expected_and_keep_the_value() {
        let mut s = LabScenario::default();
        let issue = params::set(&mut s, "weights", "heavy").expect("refused");
        assert!(issue.to_string().contains("two-modes"), "{issue}");
        assert_eq!(s.weights, LabWeights::Preset(WeightPreset::TwoModes));
        assert!(params::set(&mut s, "methods", "bogus").is_some());
        assert_eq!(s.methods, Resampler::ALL.to_vec());
        // Out of range: clamped with a message.
        assert!(params::set(&mut s, "particles", "0").is_some());
        assert_eq!(s.particles, 1);
        assert!(params::set(&mut s, "particles", "100000").is_some());
        assert_eq!(s.particles, MAX_LAB_PARTICLES);
    }

    #[test]
    fn zero_negative_and_nan_weights_open_with_a_note_and_uniform_weights() {
        let mut s = LabScenario::default();
        assert_eq!(params::set(&mut s, "weights", "0,0,0,0"), None);
        let run = LabRun::new(s.clone());
        assert_eq!(run.lab().weights(), &[0.25; 4]);
        assert!(run.note().is_some());
        assert_eq!(params::set(&mut s, "weights", "-1,NaN,2,2"), None);
        let run = LabRun::new(s);
        assert_eq!(run.lab().weights(), &[0.0, 0.0, 0.5, 0.5]);
        assert!(
            run.note().expect("a note").contains("negative"),
            "{:?}",
            run.note()
        );
    }

    #[test]
    fn undo_replays_the_earlier_presses_exactly() {
        let mut run = LabRun::new(LabScenario::default());
        run.press(1);
        run.press(40);
        let after_two = run.lab().clone();
        run.press(7);
        assert_eq!(run.resamplings(), 48);
        assert!(run.undo());
        assert_eq!(run.press_count(), 2);
        for method in Resampler::ALL {
            assert_eq!(run.lab().last_copies(method), after_two.last_copies(method));
            assert_eq!(
                run.lab().stats(method).map(|s| s.variances()),
                after_two.stats(method).map(|s| s.variances())
            );
        }
        assert!(run.undo() && run.undo());
        assert!(!run.undo(), "nothing left to take back");
    }

    #[test]
    fn the_binomial_law_sums_to_one_and_has_the_multinomial_mean_and_variance() {
        let run = LabRun::new(LabScenario::default());
        let m = run.particles();
        for i in [0, run.focus(), m - 1] {
            let p: Vec<f64> = (0..=m).map(|k| run.binomial_pmf(i, k)).collect();
            let total: f64 = p.iter().sum();
            let mean: f64 = p.iter().enumerate().map(|(k, p)| k as f64 * p).sum();
            let var: f64 = p
                .iter()
                .enumerate()
                .map(|(k, p)| (k as f64 - mean).powi(2) * p)
                .sum();
            assert!((total - 1.0).abs() < 1e-12, "{total}");
            assert!((mean - run.lab().expected_copies()[i]).abs() < 1e-12);
            assert!((var - run.multinomial_variance_of(i)).abs() < 1e-12);
        }
    }

    #[test]
    fn low_variance_reaches_the_least_variance_and_multinomial_the_binomial_one() {
        // Seeded: 4000 resamplings of the two-modes row. The lower bound f(1 − f)
        // is met by low-variance resampling up to sampling error, and multinomial's
        // counts scatter as the binomial law says.
        let mut run = LabRun::new(LabScenario::default());
        run.press(4000);
        let lv = run
            .lab()
            .stats(Resampler::LowVariance)
            .expect("low-variance")
            .variances();
        let mn = run
            .lab()
            .stats(Resampler::Multinomial)
            .expect("multinomial")
            .variances();
        for i in 0..run.particles() {
            let least = run.least_variance_of(i);
            let binomial = run.multinomial_variance_of(i);
            assert!(lv[i] <= least + 0.03, "particle {i}: {} vs {least}", lv[i]);
            assert!(
                (mn[i] - binomial).abs() <= 0.1 * binomial + 0.01,
                "particle {i}: {} vs {binomial}",
                mn[i]
            );
        }
    }

    #[test]
    fn changing_what_is_shown_keeps_the_records_and_new_weights_start_over() {
        let mut run = LabRun::new(LabScenario::default());
        run.press(10);
        let mut shown = run.scenario().clone();
        shown.presses = 50;
        shown.focus = Some(3);
        assert!(!run.reconfigure(shown));
        assert_eq!((run.resamplings(), run.focus()), (10, 3));
        let mut other = run.scenario().clone();
        other.seed = 2;
        assert!(run.reconfigure(other));
        assert_eq!(run.resamplings(), 0);
    }

    #[test]
    fn the_focus_is_the_heaviest_particle_unless_chosen() {
        let mut s = LabScenario::default();
        params::set(&mut s, "weights", "1,3,2");
        let mut run = LabRun::new(s);
        assert_eq!(run.focus(), 1);
        run.set_focus(2);
        assert_eq!(run.focus(), 2);
        run.set_focus(150);
        assert_eq!(
            run.focus(),
            1,
            "a particle that is not there falls back to the heaviest"
        );
    }
}
