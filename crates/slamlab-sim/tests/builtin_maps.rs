//! The built-in maps: a deterministic generator for `assets/maps/{maze,office}`
//! and a check that the committed files are what it produces.
//!
//! Regenerate the files with
//! `cargo test -p slamlab-sim --test builtin_maps -- --ignored regenerate`.

#![allow(clippy::panic, clippy::unwrap_used, clippy::expect_used)] // a failing test stops

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use slamlab_core::Pose2;
use slamlab_core::grid::{Cell, OccupancyGrid};
use slamlab_sim::grid::BuiltinMap;
use slamlab_sim::io::ros_map::{ImageFormat, export_map};

/// Fills the cell rectangle `[i0, i1) x [j0, j1)`.
fn fill(g: &mut OccupancyGrid, i0: i64, j0: i64, i1: i64, j1: i64, c: Cell) {
    for j in j0..j1 {
        for i in i0..i1 {
            g.set(i, j, c);
        }
    }
}

/// The maze: 10 x 10 maze cells of 20 px (1 m) with 2 px (0.1 m) walls, so
/// corridors are 0.9 m wide; carved by a seeded depth-first search (many dead
/// ends), then six walls removed for loops, a 2 x 2 room with a pillar, a 2 x 1
/// room with an L-shaped wall, and two small pillars in corridors' junctions.
fn maze() -> OccupancyGrid {
    const N: usize = 10;
    const P: i64 = 20;
    let size = N as i64 * P + 2;
    let mut g = OccupancyGrid::filled(
        size as usize,
        size as usize,
        0.05,
        Pose2::IDENTITY,
        Cell::Occupied,
    )
    .unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(2024);
    // Open every maze cell's interior.
    for cy in 0..N as i64 {
        for cx in 0..N as i64 {
            fill(
                &mut g,
                cx * P + 2,
                cy * P + 2,
                cx * P + P,
                cy * P + P,
                Cell::Free,
            );
        }
    }
    let open_between = |g: &mut OccupancyGrid, a: (i64, i64), b: (i64, i64)| {
        let (x0, y0) = (a.0.min(b.0), a.1.min(b.1));
        if a.0 != b.0 {
            // East wall of (x0, y0).
            fill(
                g,
                x0 * P + P,
                y0 * P + 2,
                x0 * P + P + 2,
                y0 * P + P,
                Cell::Free,
            );
        } else {
            fill(
                g,
                x0 * P + 2,
                y0 * P + P,
                x0 * P + P,
                y0 * P + P + 2,
                Cell::Free,
            );
        }
    };
    let mut visited = [[false; N]; N];
    let mut stack = vec![(0i64, 0i64)];
    visited[0][0] = true;
    while let Some(&(x, y)) = stack.last() {
        let mut next = Vec::new();
        for (dx, dy) in [(1, 0), (-1, 0), (0, 1), (0, -1)] {
            let (nx, ny) = (x + dx, y + dy);
            if nx >= 0
                && ny >= 0
                && nx < N as i64
                && ny < N as i64
                && !visited[ny as usize][nx as usize]
            {
                next.push((nx, ny));
            }
        }
        if next.is_empty() {
            stack.pop();
            continue;
        }
        let n = next[rng.random_range(0..next.len())];
        visited[n.1 as usize][n.0 as usize] = true;
        open_between(&mut g, (x, y), n);
        stack.push(n);
    }
    // Loops: remove a few interior walls.
    for _ in 0..6 {
        let x = rng.random_range(0..N as i64 - 1);
        let y = rng.random_range(0..N as i64 - 1);
        if rng.random::<bool>() {
            open_between(&mut g, (x, y), (x + 1, y));
        } else {
            open_between(&mut g, (x, y), (x, y + 1));
        }
    }
    // A 2 x 2 room at maze cells (6..8, 6..8) with a 0.3 m square pillar.
    fill(&mut g, 6 * P + 2, 6 * P + 2, 8 * P, 8 * P, Cell::Free);
    fill(
        &mut g,
        7 * P - 3,
        7 * P - 3,
        7 * P + 3,
        7 * P + 3,
        Cell::Occupied,
    );
    // A 2 x 1 room at (1..3, 3) with an L-shaped wall inside.
    fill(&mut g, P + 2, 3 * P + 2, 3 * P, 4 * P, Cell::Free);
    fill(
        &mut g,
        2 * P - 4,
        3 * P + 8,
        2 * P + 6,
        3 * P + 10,
        Cell::Occupied,
    );
    fill(
        &mut g,
        2 * P + 4,
        3 * P + 8,
        2 * P + 6,
        3 * P + 16,
        Cell::Occupied,
    );
    // Pillars of 0.15 m in two maze cells.
    for (cx, cy) in [(3, 8), (8, 2)] {
        fill(
            &mut g,
            cx * P + 9,
            cy * P + 9,
            cx * P + 12,
            cy * P + 12,
            Cell::Occupied,
        );
    }
    g
}

/// The office: 55 x 55 m at 0.1 m. Corridors 2 m wide at x and y = 9..11,
/// 26..28, 43..45 m; each of the 16 blocks between them is a hall with pillars
/// (one block), or rows of offices 3.5 - 6 m wide with 1 m doors onto the
/// corridors (blocks deeper than 10 m have two rows, the inner room a suite
/// reached through the outer one), some with tables.
fn office() -> OccupancyGrid {
    let res = 0.1;
    let n = 550;
    let mut g = OccupancyGrid::filled(n, n, res, Pose2::IDENTITY, Cell::Free).unwrap();
    let c = |m: f64| (m / res).round() as i64;
    let rect = |g: &mut OccupancyGrid, x0: f64, y0: f64, x1: f64, y1: f64, cell: Cell| {
        fill(g, c(x0), c(y0), c(x1), c(y1), cell)
    };
    let t = 0.2;
    // Outer wall.
    rect(&mut g, 0.0, 0.0, 55.0, t, Cell::Occupied);
    rect(&mut g, 0.0, 55.0 - t, 55.0, 55.0, Cell::Occupied);
    rect(&mut g, 0.0, 0.0, t, 55.0, Cell::Occupied);
    rect(&mut g, 55.0 - t, 0.0, 55.0, 55.0, Cell::Occupied);
    let spans = [(0.0, 9.0), (11.0, 26.0), (28.0, 43.0), (45.0, 55.0)];
    let mut rng = ChaCha8Rng::seed_from_u64(55);
    for (bi, &(x0, x1)) in spans.iter().enumerate() {
        for (bj, &(y0, y1)) in spans.iter().enumerate() {
            // Block outline.
            rect(&mut g, x0, y0, x1, y0 + t, Cell::Occupied);
            rect(&mut g, x0, y1 - t, x1, y1, Cell::Occupied);
            rect(&mut g, x0, y0, x0 + t, y1, Cell::Occupied);
            rect(&mut g, x1 - t, y0, x1, y1, Cell::Occupied);
            let corridor_below = bj > 0;
            let corridor_above = bj < 3;
            if (bi, bj) == (1, 2) {
                // The hall: doors on all four sides, pillars every 3.5 m.
                for (dx, dy) in [(0.5, 0.0), (0.5, 1.0)] {
                    let x = x0 + dx * (x1 - x0);
                    let y = if dy == 0.0 { y0 } else { y1 - t };
                    rect(&mut g, x - 1.0, y, x + 1.0, y + t, Cell::Free);
                }
                let ym = 0.5 * (y0 + y1);
                rect(&mut g, x0, ym - 1.0, x0 + t, ym + 1.0, Cell::Free);
                rect(&mut g, x1 - t, ym - 1.0, x1, ym + 1.0, Cell::Free);
                let mut px = x0 + 3.0;
                while px < x1 - 2.5 {
                    let mut py = y0 + 3.0;
                    while py < y1 - 2.5 {
                        rect(&mut g, px, py, px + 0.4, py + 0.4, Cell::Occupied);
                        py += 3.5;
                    }
                    px += 3.5;
                }
                continue;
            }
            // Room columns along x.
            let mut xs = vec![x0];
            let mut x = x0;
            loop {
                let w = rng.random_range(3.5..6.0);
                if x1 - (x + w) < 3.0 {
                    break;
                }
                x += w;
                xs.push(x);
            }
            xs.push(x1);
            for &xw in &xs[1..xs.len() - 1] {
                rect(&mut g, xw - t / 2.0, y0, xw + t / 2.0, y1, Cell::Occupied);
            }
            let two_rows = y1 - y0 > 10.0;
            let ym = 0.5 * (y0 + y1);
            if two_rows {
                rect(&mut g, x0, ym - t / 2.0, x1, ym + t / 2.0, Cell::Occupied);
            }
            for k in 0..xs.len() - 1 {
                let (rx0, rx1) = (xs[k], xs[k + 1]);
                let door = |rng: &mut ChaCha8Rng| rng.random_range(rx0 + 0.6..rx1 - 1.6);
                let rows: Vec<(f64, f64)> = if two_rows {
                    vec![(y0, ym), (ym, y1)]
                } else {
                    vec![(y0, y1)]
                };
                for &(ry0, ry1) in &rows {
                    let below = corridor_below && ry0 == y0;
                    let above = corridor_above && ry1 == y1;
                    if below {
                        let d = door(&mut rng);
                        rect(&mut g, d, y0, d + 1.0, y0 + t, Cell::Free);
                    }
                    if above {
                        let d = door(&mut rng);
                        rect(&mut g, d, y1 - t, d + 1.0, y1, Cell::Free);
                    }
                    if !below && !above {
                        // A suite: a door into the neighbouring row.
                        let d = door(&mut rng);
                        rect(&mut g, d, ym - t, d + 1.0, ym + t, Cell::Free);
                    }
                    // Tables in about a third of the rooms.
                    if rng.random::<f64>() < 0.35 && rx1 - rx0 > 3.9 && ry1 - ry0 > 3.9 {
                        let tables = rng.random_range(1..=2);
                        for _ in 0..tables {
                            let (tw, th) = if rng.random::<bool>() {
                                (1.4, 0.7)
                            } else {
                                (0.7, 1.4)
                            };
                            let tx = rng.random_range(rx0 + 1.0..rx1 - 1.0 - tw);
                            let ty = rng.random_range(ry0 + 1.2..ry1 - 1.2 - th);
                            rect(&mut g, tx, ty, tx + tw, ty + th, Cell::Occupied);
                        }
                    }
                }
                // The end rooms of a row open onto a side corridor as well.
                if (k == 0 && bi > 0) || (k == xs.len() - 2 && bi < 3) {
                    let side = if k == 0 { rx0 } else { rx1 - t };
                    let (ry0, ry1) = rows[0];
                    let d = rng.random_range(ry0 + 0.6..ry1 - 1.6);
                    rect(&mut g, side, d, side + t, d + 1.0, Cell::Free);
                }
            }
        }
    }
    g
}

fn assets() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/maps")
}

#[test]
#[ignore = "rewrites assets/maps; run by hand after changing a generator"]
fn regenerate() {
    for (name, grid) in [("maze", maze()), ("office", office())] {
        let (yaml, png) = export_map(&grid, &format!("{name}.png"), ImageFormat::Png).unwrap();
        std::fs::write(assets().join(format!("{name}.yaml")), yaml).unwrap();
        std::fs::write(assets().join(format!("{name}.png")), png).unwrap();
    }
}

#[test]
fn committed_maps_are_the_generators_output() {
    let maze_grid = BuiltinMap::Maze.load().unwrap();
    assert_eq!(maze_grid, maze());
    assert_eq!((maze_grid.width(), maze_grid.height()), (202, 202));
    let office_grid = BuiltinMap::Office.load().unwrap();
    assert_eq!(office_grid, office());
    assert_eq!((office_grid.width(), office_grid.height()), (550, 550));
    let (free, occ, unknown) = maze_grid.counts();
    assert_eq!(unknown, 0);
    assert!(free > 30_000 && occ > 4_000, "{free} {occ}");
}
