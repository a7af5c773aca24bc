//! The parameter rows of a simulated lidar run that the mapping and
//! Cartographer lessons share (`seed`, `map`, `steps`): the same names, ranges
//! and help in both tables, written once here and listed by each table for its
//! scenario through [`SimulatedRun`].

use crate::params::{Param, Scenario, choose};

/// The built-in maps a simulated robot can explore, as the `map` parameter
/// names them (see [`super::BuiltinMap`]).
const MAPS: &[&str] = &["maze", "office"];

/// A lidar lesson's scenario with a simulated robot's run: the seed of every
/// random stream ([`Scenario::seed`]), the map it explores (a built-in map's
/// name or a ROS map file's location) and the scans it records.
pub trait SimulatedRun: Scenario {
    /// The map and the number of scans.
    fn run(&self) -> (&str, usize);
    /// The seed, the map and the number of scans, to change them.
    fn run_mut(&mut self) -> (&mut u64, &mut String, &mut usize);
}

/// The `seed` row: the seed of every random stream.
pub const fn seed_param<S: SimulatedRun>() -> Param<S> {
    Param::count(
        "seed",
        "",
        "seed of every random stream",
        (0, u64::MAX),
        |s| Some(s.seed()),
        |s, v| *s.run_mut().0 = v,
    )
}

/// The `map` row: a built-in map's name, or a ROS map file's location
/// (`.yaml` or `.yml`, read by the app and the CLI).
pub const fn map_param<S: SimulatedRun>() -> Param<S> {
    Param::words(
        "map",
        "built-in map the simulated robot explores (or drop a ROS map or a laser log on the app's window)",
        MAPS,
        |s| Some(s.run().0.to_owned()),
        |s, v| {
            let map = s.run_mut().1;
            if v.ends_with(".yaml") || v.ends_with(".yml") {
                *map = v.to_owned();
                Ok(())
            } else {
                choose(MAPS, v).map(|i| *map = MAPS[i].to_owned())
            }
        },
    )
}

/// The `steps` row: scans the simulated robot records, 0.1 s apart.
pub const fn steps_param<S: SimulatedRun>() -> Param<S> {
    Param::count(
        "steps",
        "",
        "scans the simulated robot records (0.1 s apart)",
        (1, 20_000),
        |s| Some(s.run().1 as u64),
        |s, v| *s.run_mut().2 = usize::try_from(v).unwrap_or(20_000),
    )
}
