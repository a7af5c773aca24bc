//! Pose-graph files: round trips, TORO's information order, Victoria Park, and
//! refusals that name the line; and the thesis simulation's golden run.

#![allow(clippy::panic, clippy::unwrap_used, clippy::expect_used)] // a failing test stops

use nalgebra::{Matrix2, Matrix3, Vector2};
use slamlab_core::Pose2;
use slamlab_core::graph::{EdgeKind, PoseGraph, VertexState};
use slamlab_sim::io::graph::{GraphFileError, GraphFormat, MAX_FILE_BYTES, read_graph, write_g2o};
use slamlab_sim::pose_graph::experiment::{self, PoseGraphExperimentConfig};

fn shared(file: &str) -> Option<String> {
    let path = format!(
        "{}/../../../shared/data/posegraphs/{file}",
        env!("CARGO_MANIFEST_DIR")
    );
    match std::fs::read_to_string(&path) {
        Ok(t) => Some(t),
        Err(_) => {
            println!("skipped: ../shared/data/posegraphs/{file} not found");
            None
        }
    }
}

fn sample_graph() -> PoseGraph {
    let mut g = PoseGraph::new();
    let a = g.add_pose(3, Pose2::new(0.1, -0.2, 3.1)).unwrap();
    let b = g.add_pose(8, Pose2::new(1.0 / 3.0, 2.5e-7, -1.0)).unwrap();
    let l = g.add_point(20, Vector2::new(4.0, -2.0 / 7.0)).unwrap();
    g.set_fixed(3, true).unwrap();
    let mut info = Matrix3::new(
        44.4483,
        1.13546,
        6.95335e-310,
        1.13546,
        376.08,
        0.0,
        6.95335e-310,
        0.0,
        9807.72,
    );
    info[(1, 2)] = 0.5;
    info[(2, 1)] = 0.5;
    g.add_edge(EdgeKind::PosePose {
        from: a,
        to: b,
        measurement: Pose2::new(0.3, 0.1, -0.7),
        information: info,
    })
    .unwrap();
    g.add_edge(EdgeKind::PosePoint {
        pose: b,
        point: l,
        measurement: Vector2::new(1.5, 0.25),
        information: Matrix2::new(10.0, 1.0, 1.0, 20.0),
    })
    .unwrap();
    g.add_edge(EdgeKind::PosePrior {
        pose: b,
        measurement: Pose2::new(0.3, 0.0, -1.0),
        information: Matrix3::identity() * 1e6,
    })
    .unwrap();
    g
}

fn assert_same(a: &PoseGraph, b: &PoseGraph) {
    assert_eq!(a.vertices(), b.vertices());
    assert_eq!(a.edges(), b.edges());
}

#[test]
fn g2o_write_then_read_gives_the_same_graph() {
    let g = sample_graph();
    let text = write_g2o(&g).unwrap();
    assert!(text.contains("FIX 3"), "{text}");
    assert!(
        text.contains("6.95335e-310"),
        "the denormal survives: {text}"
    );
    let back = read_graph(&text).unwrap();
    assert_same(&g, &back);
    // And once more: the text is a fixed point.
    assert_eq!(write_g2o(&back).unwrap(), text);
}

#[test]
fn toro_information_order_is_mapped() {
    // Ixx Ixy Iyy Itt Ixt Iyt = 1 2 30 400 5 6
    let text = "# hand-made TORO file\nVERTEX2 0 0 0 0\nVERTEX2 1 1 0 0.5\nEDGE2 0 1 1 0 0.5 1 2 30 400 5 6\n";
    assert_eq!(
        slamlab_sim::io::graph::detect_format(text).unwrap(),
        GraphFormat::Toro
    );
    let g = read_graph(text).unwrap();
    let EdgeKind::PosePose { information, .. } = g.edges()[0] else {
        panic!("pose-pose edge expected")
    };
    let expected = Matrix3::new(1.0, 2.0, 5.0, 2.0, 30.0, 6.0, 5.0, 6.0, 400.0);
    assert_eq!(information, expected);
    // The same numbers as g2o (I11 I12 I13 I22 I23 I33) give another matrix.
    let g2o = read_graph(
        "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0.5\nEDGE_SE2 0 1 1 0 0.5 1 2 5 30 6 400\n",
    )
    .unwrap();
    assert_eq!(g2o.edges()[0], g.edges()[0]);
}

fn line_of(e: GraphFileError) -> (usize, String) {
    match e {
        GraphFileError::Line { line, message } => (line, message),
        other => panic!("a line error expected, got {other}"),
    }
}

#[test]
fn bad_files_are_refused_with_the_line_and_the_reason() {
    let v = "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\n";
    let cases = [
        (
            format!("{v}EDGE_SE2 0 7 1 0 0 1 0 0 1 0 1\n"),
            3,
            "vertex 7",
        ),
        (format!("{v}VERTEX_SE2 1 2 0 0\n"), 3, "defined twice"),
        (
            format!("{v}EDGE_SE2 0 1 nan 0 0 1 0 0 1 0 1\n"),
            3,
            "not a finite number",
        ),
        (format!("{v}EDGE_SE2 0 1 1 0 0 0 0 0 0 0 0\n"), 3, "is zero"),
        (
            format!("{v}EDGE_SE2 0 1 1 0 0 1 0 0 -1 0 1\n"),
            3,
            "not positive semi-definite",
        ),
        (
            format!("{v}EDGE_SE2 0 1 1 0 0 1 0 0 1 0\n"),
            3,
            "needs 11 numbers",
        ),
        (
            format!("{v}EDGE_SE2 0 1 1 0 zero 1 0 0 1 0 1\n"),
            3,
            "'zero' is not a number",
        ),
        (format!("{v}EDGE_SE3:QUAT 0 1\n"), 3, "not a g2o 2D entry"),
        (
            format!("{v}FIX 9\nEDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\n"),
            3,
            "FIX names vertex 9",
        ),
        ("ODOMETRY 0 1 1 0 0 0 0 0 0 0 0\n".to_owned(), 1, "singular"),
        (
            "ODOMETRY 0 1 1 0 0 1 0 0 1 0 1\nLANDMARK 5 2 1 1 0.4 0 0.4\n".to_owned(),
            2,
            "pose 5",
        ),
    ];
    for (text, line, needle) in cases {
        let (l, message) = line_of(read_graph(&text).unwrap_err());
        assert_eq!(l, line, "{message}");
        assert!(
            message.contains(needle),
            "'{message}' should mention '{needle}'"
        );
    }
    let one = read_graph("VERTEX_SE2 0 0 0 0\n").unwrap_err();
    assert!(one.to_string().contains("1 vertex"), "{one}");
    let none = read_graph("hello world\n").unwrap_err();
    assert!(
        none.to_string().contains("line 1 starts with 'hello'"),
        "{none}"
    );
    let big = "#".repeat(MAX_FILE_BYTES + 1);
    assert!(matches!(
        read_graph(&big),
        Err(GraphFileError::TooLarge { .. })
    ));
}

#[test]
fn frh_denormal_information_is_read() {
    let Some(text) = shared("FRH.g2o") else {
        return;
    };
    let g = read_graph(&text).unwrap();
    assert_eq!((g.vertices().len(), g.edges().len()), (1316, 2820));
    let EdgeKind::PosePose { information, .. } = g.edges()[0] else {
        panic!("pose-pose expected")
    };
    assert_eq!(information[(0, 2)], 6.95335e-310);
}

#[test]
fn victoria_park_loads_with_its_151_landmarks() {
    let Some(text) = shared("victoria_park.txt") else {
        return;
    };
    let g = read_graph(&text).unwrap();
    assert_eq!(g.pose_count(), 6969);
    assert_eq!(g.point_count(), 151);
    assert_eq!(g.edges().len(), 6968 + 3640);
    // Landmarks are numbered after the poses: base 10000.
    assert!(
        g.vertex(10005)
            .is_some_and(|v| matches!(v.state, VertexState::Point(_)))
    );
    // The initial estimate chains the odometry: pose 1 is the first odometry step.
    let VertexState::Pose(p1) = g.vertex(1).unwrap().state else {
        panic!("pose expected")
    };
    assert!((p1.x - 0.000985144).abs() < 1e-12);
}

#[test]
fn thesis_simulation_converges_in_a_few_iterations_and_lands_closest_to_the_truth() {
    for noise_scale in [1.0, 2.0] {
        let r = experiment::run(PoseGraphExperimentConfig {
            noise_scale,
            ..PoseGraphExperimentConfig::default()
        })
        .unwrap();
        assert_eq!(r.poses, 201);
        assert_eq!(r.edges, 200 + 10);
        assert_eq!(r.loop_closure_nodes.len(), 10);
        // Gauss-Newton: within 0.1 % of the final cost after two iterations.
        assert!(r.costs.len() <= 6, "{:?}", r.costs);
        assert!(r.costs[1] <= r.final_cost * 1.001, "{:?}", r.costs);
        assert!(r.final_cost < 0.1 * r.initial_cost);
        assert!(r.rmse_optimized < r.rmse_ekf, "{r:?}");
        assert!(r.rmse_ekf < r.rmse_dead_reckoning, "{r:?}");
    }
}

#[test]
fn manhattan_graph_has_loop_closures_and_optimizes_close_to_the_truth() {
    let (g, truth) = experiment::manhattan_graph(400, 10, 3);
    assert_eq!(g.pose_count(), 400);
    let closures = g.edges().len() - 399;
    assert!(closures > 50, "{closures} loop closures");
    let mut opt = slamlab_core::graph::Optimizer::new(g, Default::default()).unwrap();
    let start = opt.cost();
    opt.optimize(50, |_| true).unwrap();
    assert!(opt.is_converged());
    // The minimum of the noise-weighted cost is χ²-distributed with (residuals −
    // unknowns) = 3 × (loop closures) degrees of freedom: within ±50 % of it.
    let dof = 3.0 * closures as f64;
    assert!(
        opt.cost() > 0.5 * dof && opt.cost() < 1.5 * dof && opt.cost() < 0.02 * start,
        "{} (start {start}, dof {dof})",
        opt.cost()
    );
    let err: f64 = truth
        .iter()
        .zip(opt.graph().vertices())
        .map(|(t, v)| (v.state.position() - t.translation()).norm_squared())
        .sum::<f64>()
        / 400.0;
    assert!(err.sqrt() < 0.5, "position RMSE {}", err.sqrt());
}
