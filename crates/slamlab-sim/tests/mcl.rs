//! Monte Carlo localization on the built-in maze and, when present, the real
//! maps in `../shared/data/maps`.

use slamlab_sim::grid::BuiltinMap;
use slamlab_sim::localization::{InitMode, MclRun, MclScenario};

fn maze_run(init: InitMode, particles: usize, seed: u64) -> MclRun {
    let scenario = MclScenario {
        init,
        max_particles: particles,
        seed,
        ..Default::default()
    };
    MclRun::new(scenario, BuiltinMap::Maze.load().unwrap()).unwrap()
}

#[test]
#[ignore = "probe"]
fn probe() {
    for seed in 1..=10 {
        let mut run = maze_run(InitMode::Global, 5000, seed);
        run.run_ticks(600);
        let s = &run.summaries()[0];
        let f = &run.filters()[0];
        println!(
            "seed {seed}: {:?} updates {} notes {} final {:?}",
            s.converged_tick,
            f.updates.len(),
            run.notes().len(),
            s.position_error_final
        );
    }
}
