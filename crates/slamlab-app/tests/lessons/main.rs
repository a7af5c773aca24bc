//! The app's UI tests through egui_kittest, one test binary for every lesson
//! (one link of the app instead of one per lesson): each lesson opens by URL,
//! its buttons do what they say, bad input gets a message, and the rendered
//! window has the colours a student must see.

#![allow(clippy::panic)]

mod common;

mod assignment_ui;
mod cartographer_ui;
mod estimates_ui;
mod exports_ui;
mod filters_ui;
mod fusion_ui;
mod kidnap_ui;
mod landmark_data_ui;
mod landmark_fastslam_ui;
mod landmark_ui;
mod mapping_ui;
mod pose_graph_ui;
mod resampling_ui;
mod shell_ui;
mod sources_ui;
mod steady_screen_ui;
mod visual_odometry_ui;
