//! Time for any lesson: a generic stepper that runs a simulation one phase at a
//! time, records the live events that change it (a drive command, a sensor
//! change, a kidnap), keeps checkpoints within a memory budget, and steps back by
//! restoring the latest checkpoint and replaying.
//!
//! A lesson provides a [`Simulation`]: its state is everything a checkpoint must
//! hold (the truth, the estimators with their random streams, the noise streams),
//! and a clone of it *is* a checkpoint. What only grows (paths, metrics per tick)
//! lives in its [`Records`], outside the checkpoints: stepping back truncates them
//! to the checkpoint's marks instead of copying them.
//!
//! A run is deterministic given its start and its events, so stepping back is
//! exact: the replay meets every event at the phase it was applied at.

use std::collections::VecDeque;
use std::fmt::Debug;

/// What grows during a run and is kept outside the checkpoints.
pub trait Records: Debug {
    /// A position in the records (their lengths).
    type Mark: Clone + Debug + PartialEq;
    /// Where the records stand now.
    fn mark(&self) -> Self::Mark;
    /// Drops everything recorded after `mark`.
    fn truncate(&mut self, mark: &Self::Mark);
}

/// No records: for a simulation that keeps its short histories in its own state.
impl Records for () {
    type Mark = ();
    fn mark(&self) {}
    fn truncate(&mut self, _mark: &()) {}
}

/// A lesson's simulation, stepped one phase at a time.
pub trait Simulation: Clone + Debug {
    /// One step within a tick ("predict", "update landmark 7", "resample").
    type Phase: Clone + Debug;
    /// A live change applied between phases and recorded for replay.
    type Event: Clone + Debug;
    /// What the run records tick by tick.
    type Records: Records;

    /// Runs the next phase, beginning a new tick when the last one is finished,
    /// and returns it.
    fn step_phase(&mut self, records: &mut Self::Records) -> Self::Phase;
    /// True between the first and the last phase of a tick.
    fn is_mid_tick(&self) -> bool;
    /// Ticks begun so far.
    fn tick(&self) -> u64;
    /// Applies a live event (invalid ones do nothing, so replays stay exact).
    fn apply_event(&mut self, event: &Self::Event);
    /// About how many bytes one checkpoint (a clone) takes.
    fn checkpoint_bytes(&self) -> usize;
}

/// How often checkpoints are taken and how much memory they may use.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CheckpointPolicy {
    /// Ticks between two checkpoints.
    pub every_ticks: u64,
    /// At most this many checkpoints are kept (the oldest go first)...
    pub max_checkpoints: usize,
    /// ...and together at most about this many bytes.
    pub budget_bytes: usize,
}

impl Default for CheckpointPolicy {
    fn default() -> Self {
        Self {
            every_ticks: 50,
            max_checkpoints: 20,
            budget_bytes: 64 << 20,
        }
    }
}

#[derive(Debug)]
struct Checkpoint<S: Simulation> {
    phases_run: u64,
    state: S,
    mark: <S::Records as Records>::Mark,
}

impl<S: Simulation> Clone for Checkpoint<S> {
    fn clone(&self) -> Self {
        Self {
            phases_run: self.phases_run,
            state: self.state.clone(),
            mark: self.mark.clone(),
        }
    }
}

/// Runs a [`Simulation`] phase by phase, with events, checkpoints and step back.
#[derive(Debug)]
pub struct Stepper<S: Simulation> {
    sim: S,
    records: S::Records,
    phases_run: u64,
    last_phase: Option<S::Phase>,
    /// Every event with the number of phases run when it was applied, in order.
    events: Vec<(u64, S::Event)>,
    /// Events before this index have been applied to `sim`; the rest were recorded
    /// before a step back and apply again when the run gets there.
    applied_events: usize,
    /// The start (phase 0) and then one checkpoint every `policy.every_ticks` ticks.
    start: Checkpoint<S>,
    checkpoints: VecDeque<Checkpoint<S>>,
    policy: CheckpointPolicy,
}

impl<S: Simulation> Stepper<S> {
    /// Starts stepping `sim`, whose records start as `records`.
    pub fn new(sim: S, records: S::Records) -> Self {
        Self::with_policy(sim, records, CheckpointPolicy::default())
    }

    /// As [`new`](Self::new), with a checkpoint policy.
    pub fn with_policy(sim: S, records: S::Records, policy: CheckpointPolicy) -> Self {
        let start = Checkpoint {
            phases_run: 0,
            state: sim.clone(),
            mark: records.mark(),
        };
        Self {
            sim,
            records,
            phases_run: 0,
            last_phase: None,
            events: Vec::new(),
            applied_events: 0,
            start,
            checkpoints: VecDeque::new(),
            policy,
        }
    }

    /// The simulation now.
    pub fn sim(&self) -> &S {
        &self.sim
    }

    /// The records so far.
    pub fn records(&self) -> &S::Records {
        &self.records
    }

    /// Phases run since the start.
    pub fn phases_run(&self) -> u64 {
        self.phases_run
    }

    /// The phase that ran last (none at the start or right after stepping back to it).
    pub fn last_phase(&self) -> Option<&S::Phase> {
        self.last_phase.as_ref()
    }

    /// Every event applied or recorded, with the phase count it applies at.
    pub fn events(&self) -> &[(u64, S::Event)] {
        &self.events
    }

    /// Applies a live event now and records it. Events recorded later than now
    /// (before a step back) are dropped: the run takes a new course from here.
    pub fn apply(&mut self, event: S::Event) {
        self.events.truncate(self.applied_events);
        self.sim.apply_event(&event);
        self.events.push((self.phases_run, event));
        self.applied_events = self.events.len();
    }

    /// Runs the next phase and returns it.
    pub fn step_phase(&mut self) -> S::Phase {
        let phase = self.sim.step_phase(&mut self.records);
        self.phases_run += 1;
        self.last_phase = Some(phase.clone());
        if !self.sim.is_mid_tick() {
            self.maybe_checkpoint();
        }
        self.apply_recorded_events();
        phase
    }

    /// Finishes the current tick, or runs a whole new one.
    pub fn step_tick(&mut self) {
        loop {
            self.step_phase();
            if !self.sim.is_mid_tick() {
                break;
            }
        }
    }

    /// Runs `count` whole ticks.
    pub fn run_ticks(&mut self, count: u64) {
        for _ in 0..count {
            self.step_tick();
        }
    }

    /// The phases a [`step_back`](Self::step_back) would replay now.
    pub fn step_back_replay_length(&self) -> u64 {
        let Some(target) = self.phases_run.checked_sub(1) else {
            return 0;
        };
        target - self.checkpoint_before(target).phases_run
    }

    /// Goes back one phase: the run becomes exactly what it was before the last
    /// phase ran (with the events applied at that point). Returns `false` at the start.
    pub fn step_back(&mut self) -> bool {
        let Some(target) = self.phases_run.checked_sub(1) else {
            return false;
        };
        self.go_to(target);
        true
    }

    /// Replays the run to `phases` phases from the latest checkpoint at or before it.
    fn go_to(&mut self, phases: u64) {
        let checkpoint = self.checkpoint_before(phases).clone();
        self.checkpoints.retain(|c| c.phases_run <= phases);
        self.sim = checkpoint.state;
        self.records.truncate(&checkpoint.mark);
        self.phases_run = checkpoint.phases_run;
        self.last_phase = None;
        self.applied_events = self
            .events
            .iter()
            .position(|(at, _)| *at >= self.phases_run)
            .unwrap_or(self.events.len());
        self.apply_recorded_events();
        while self.phases_run < phases {
            self.step_phase();
        }
    }

    fn checkpoint_before(&self, phases: u64) -> &Checkpoint<S> {
        self.checkpoints
            .iter()
            .rev()
            .find(|c| c.phases_run <= phases)
            .unwrap_or(&self.start)
    }

    /// Applies the recorded events that are due at the current phase count.
    fn apply_recorded_events(&mut self) {
        while let Some((at, event)) = self.events.get(self.applied_events) {
            if *at != self.phases_run {
                break;
            }
            self.sim.apply_event(event);
            self.applied_events += 1;
        }
    }

    fn maybe_checkpoint(&mut self) {
        let every = self.policy.every_ticks.max(1);
        if !self.sim.tick().is_multiple_of(every)
            || self
                .checkpoints
                .back()
                .is_some_and(|c| c.phases_run >= self.phases_run)
        {
            return;
        }
        let capacity = (self.policy.budget_bytes / self.sim.checkpoint_bytes().max(1))
            .clamp(1, self.policy.max_checkpoints.max(1));
        while self.checkpoints.len() >= capacity {
            self.checkpoints.pop_front();
        }
        self.checkpoints.push_back(Checkpoint {
            phases_run: self.phases_run,
            state: self.sim.clone(),
            mark: self.records.mark(),
        });
    }

    /// Mutable access to the simulation for changes that are not part of the run
    /// (display caches). Anything that changes the outcome must be an event.
    pub fn sim_mut_untracked(&mut self) -> &mut S {
        &mut self.sim
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A random walk whose tick is two phases (move, then measure), steered by events.
    #[derive(Clone, Debug)]
    struct Walk {
        rng: ChaCha8Rng,
        position: f64,
        drift: f64,
        tick: u64,
        halfway: bool,
    }

    #[derive(Debug, Default)]
    struct Trace(Vec<f64>);

    impl Records for Trace {
        type Mark = usize;
        fn mark(&self) -> usize {
            self.0.len()
        }
        fn truncate(&mut self, mark: &usize) {
            self.0.truncate(*mark);
        }
    }

    impl Simulation for Walk {
        type Phase = &'static str;
        type Event = f64;
        type Records = Trace;
        fn step_phase(&mut self, records: &mut Trace) -> &'static str {
            if self.halfway {
                self.halfway = false;
                records.0.push(self.position);
                "measure"
            } else {
                self.tick += 1;
                self.position += self.drift + self.rng.random::<f64>() - 0.5;
                self.halfway = true;
                "move"
            }
        }
        fn is_mid_tick(&self) -> bool {
            self.halfway
        }
        fn tick(&self) -> u64 {
            self.tick
        }
        fn apply_event(&mut self, drift: &f64) {
            if drift.is_finite() {
                self.drift = *drift;
            }
        }
        fn checkpoint_bytes(&self) -> usize {
            std::mem::size_of::<Self>()
        }
    }

    fn walk() -> Stepper<Walk> {
        let sim = Walk {
            rng: ChaCha8Rng::seed_from_u64(4),
            position: 0.0,
            drift: 0.0,
            tick: 0,
            halfway: false,
        };
        let policy = CheckpointPolicy {
            every_ticks: 7,
            max_checkpoints: 3,
            budget_bytes: 1 << 20,
        };
        Stepper::with_policy(sim, Trace::default(), policy)
    }

    #[test]
    fn stepping_back_is_exact_with_events_and_checkpoints() {
        let mut s = walk();
        let mut positions = vec![0.0];
        let mut states = Vec::new();
        for i in 0..100 {
            if i % 13 == 5 {
                s.apply(f64::from(i) * 0.01);
            }
            states.push((s.sim().position, s.sim().drift, s.records().0.clone()));
            s.step_phase();
            positions.push(s.sim().position);
        }
        assert_eq!(s.phases_run(), 100);
        assert_eq!(s.checkpoints.len(), 3, "only the latest three are kept");
        // Back to the start, one phase at a time: every state is what it was.
        for i in (0..100).rev() {
            assert!(s.step_back());
            let (position, drift, trace) = &states[i];
            assert_eq!(s.sim().position, *position, "phase {i}");
            assert_eq!(s.sim().drift, *drift, "phase {i}");
            assert_eq!(&s.records().0, trace, "phase {i}");
        }
        assert!(!s.step_back());
        // Forward again: the recorded events apply where they did.
        s.run_ticks(50);
        assert_eq!(s.sim().position, positions[100]);
        assert_eq!(s.records().0.len(), 50);
    }

    #[test]
    fn a_new_event_after_stepping_back_replaces_the_recorded_future() {
        let mut s = walk();
        s.run_ticks(10);
        s.apply(1.0);
        s.run_ticks(10);
        let with_drift = s.sim().position;
        for _ in 0..30 {
            s.step_back();
        }
        assert_eq!(s.phases_run(), 10);
        s.apply(-1.0);
        s.run_ticks(10);
        assert_eq!(s.events().len(), 1);
        assert!(
            s.sim().position < with_drift - 15.0,
            "{} vs {with_drift}",
            s.sim().position
        );
        // The replay cost is bounded by the checkpoint spacing.
        assert!(s.step_back_replay_length() <= 2 * 7 + 1);
    }
}
