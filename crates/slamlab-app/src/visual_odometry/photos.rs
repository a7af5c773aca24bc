//! The student's own photos (thesis `000` Fig. 4.14): two photos opened with the
//! picker or dropped on the window, FAST corners and BRIEF descriptors matched
//! by Hamming distance with the ratio test, the same five-point RANSAC as the
//! synthetic pairs, and the matches drawn as lines across the two images,
//! inliers and outliers in the lesson's colours. A bad file leaves a message
//! and everything else as it was.

use egui::{Color32, Pos2, Rect, Stroke, TextureOptions, Vec2};
use slamlab_core::vision::{Motion, rotation_angle};
use slamlab_sim::visual_odometry::photos::{self, Photo, PhotoEstimate};

use super::images::{INLIER, OUTLIER};
use crate::widgets::dropped_files::DropInbox;
use crate::widgets::file_picker::{FilePicker, PickedFile};

/// Two photos and what the pipeline made of them.
#[derive(Default)]
pub struct PhotoPair {
    picker: FilePicker,
    inbox: DropInbox,
    left: Option<Photo>,
    right: Option<Photo>,
    /// Focal length in pixels of the photos as taken; `None`: from a 60°
    /// horizontal field of view.
    focal_px: Option<f64>,
    result: Option<Result<PhotoEstimate, String>>,
    /// The last file that could not be used, and why.
    message: Option<String>,
    textures: [Option<egui::TextureHandle>; 2],
    /// Show the photos in the centre instead of the synthetic step.
    pub show: bool,
}

impl std::fmt::Debug for PhotoPair {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PhotoPair")
            .field("left", &self.left.as_ref().map(|p| &p.name))
            .field("right", &self.right.as_ref().map(|p| &p.name))
            .field("message", &self.message)
            .finish_non_exhaustive()
    }
}

impl PhotoPair {
    /// Reads what was picked or dropped this frame.
    pub fn poll(&mut self, ctx: &egui::Context) {
        let picked = self.picker.poll_all();
        if let Some(batch) = self.inbox.poll(ctx).or(picked) {
            self.load_batch(batch);
        }
    }

    /// Loads one or two files: two at once replace both photos; one fills the
    /// empty place (or starts a new pair when both are taken).
    pub fn load_batch(&mut self, batch: Vec<PickedFile>) {
        if batch.len() >= 2 {
            let mut decoded = Vec::new();
            for (name, bytes) in batch.into_iter().take(2) {
                match self.decode(&name, bytes) {
                    Some(photo) => decoded.push(photo),
                    None => return,
                }
            }
            self.right = decoded.pop();
            self.left = decoded.pop();
        } else if let Some((name, bytes)) = batch.into_iter().next() {
            let Some(photo) = self.decode(&name, bytes) else {
                return;
            };
            if self.left.is_none() || self.right.is_some() {
                self.left = Some(photo);
                self.right = None;
            } else {
                self.right = Some(photo);
            }
        }
        self.message = None;
        self.textures = [None, None];
        self.estimate();
    }

    /// Decodes a file, or leaves a message (and the photos as they were).
    fn decode(&mut self, name: &str, bytes: Result<Vec<u8>, String>) -> Option<Photo> {
        let result = bytes.and_then(|b| photos::decode_photo(name, &b).map_err(|e| e.to_string()));
        match result {
            Ok(photo) => Some(photo),
            Err(why) => {
                self.message = Some(format!("Could not use {name}: {why}"));
                None
            }
        }
    }

    /// The focal length used, pixels of the photos as taken.
    pub fn focal_px(&self) -> Option<f64> {
        let left = self.left.as_ref()?;
        Some(
            self.focal_px
                .unwrap_or_else(|| photos::focal_for_fov(f64::from(left.original.0), 60.0)),
        )
    }

    fn estimate(&mut self) {
        self.result = match (&self.left, &self.right, self.focal_px()) {
            (Some(l), Some(r), Some(f)) => {
                self.show = true;
                Some(photos::estimate_photos(l, r, f).map_err(|e| e.to_string()))
            }
            _ => None,
        };
    }

    /// Whether the centre shows the photos.
    pub fn showing(&self) -> bool {
        self.show && self.left.is_some() && self.right.is_some()
    }

    /// The panel's controls.
    pub fn controls_ui(&mut self, ui: &mut egui::Ui) {
        ui.separator();
        ui.strong("Your photos");
        ui.label(
            "Open two photos of one scene taken a step apart (PNG or JPEG, up to 50 megapixels), \
             or drop them on the window: FAST corners, BRIEF descriptors, Hamming matching with \
             the ratio test, then the same RANSAC.",
        );
        self.picker.ui(
            ui,
            "Open photos…",
            ".png,.jpg,.jpeg",
            photos::MAX_PHOTO_BYTES,
            "path/to/photo.jpg",
        );
        let name = |p: &Option<Photo>| {
            p.as_ref().map_or("none".to_owned(), |p| {
                format!("{} ({} x {})", p.name, p.original.0, p.original.1)
            })
        };
        ui.label(format!("left: {}", name(&self.left)));
        ui.label(format!("right: {}", name(&self.right)));
        if let Some(mut focal) = self.focal_px() {
            let width = self.left.as_ref().map_or(1.0, |p| f64::from(p.original.0));
            ui.horizontal_wrapped(|ui| {
                let label = ui.label("focal length (px)");
                let response = ui
                    .add(
                        egui::DragValue::new(&mut focal)
                            .range(10.0..=100_000.0)
                            .speed(5.0),
                    )
                    .labelled_by(label.id)
                    .on_hover_text("In pixels of the photo as taken; the default is a 60° horizontal field of view");
                let fov = 2.0 * slamlab_core::math::atan(width / 2.0 / focal).to_degrees();
                ui.label(format!("= {fov:.1}° field of view"));
                if response.changed() && focal.is_finite() {
                    self.focal_px = Some(focal);
                    self.estimate();
                }
            });
        }
        if self.left.is_some() && self.right.is_some() {
            ui.checkbox(&mut self.show, "Show the photos (not the simulated step)");
        }
        if (self.left.is_some() || self.right.is_some()) && ui.button("Forget the photos").clicked()
        {
            *self = Self::default();
        }
        if let Some(message) = &self.message {
            ui.colored_label(ui.visuals().warn_fg_color, message);
        }
        if let Some(Err(why)) = &self.result {
            ui.colored_label(ui.visuals().warn_fg_color, why);
        }
    }

    /// The two photos side by side with lines between matched features
    /// (thesis Fig. 4.14), and what RANSAC found.
    pub fn centre_ui(&mut self, ui: &mut egui::Ui) {
        let (Some(left), Some(right)) = (&self.left, &self.right) else {
            return;
        };
        for (slot, photo) in [left, right].into_iter().enumerate() {
            if self.textures[slot].is_none() {
                let (w, h) = photo.gray.dimensions();
                let image =
                    egui::ColorImage::from_gray([w as usize, h as usize], photo.gray.as_raw());
                self.textures[slot] = Some(ui.ctx().load_texture(
                    format!("vo_photo_{slot}"),
                    image,
                    TextureOptions::LINEAR,
                ));
            }
        }
        match &self.result {
            Some(Ok(result)) => {
                let e = &result.estimate;
                let m = &result.matched;
                let motion = match (e.motion, e.translation) {
                    (Motion::General, Some(t)) => {
                        format!("t direction ({:.2}, {:.2}, {:.2})", t.x, t.y, t.z)
                    }
                    _ => format!(
                        "a pure rotation: t unobservable (median parallax {:.2} px, below {} px: \
                         the same photo twice, or both taken from one place)",
                        e.parallax_px,
                        slamlab_core::vision::RansacConfig::default().min_parallax_px
                    ),
                };
                ui.label(format!(
                    "{} and {} corners, {} matches ({} dropped by the ratio test), {} inliers after {} samples; \
                     rotation {:.2}°, {motion}",
                    m.features.0,
                    m.features.1,
                    m.matches.len(),
                    m.ambiguous,
                    e.inlier_count,
                    e.iterations,
                    rotation_angle(&e.rotation).to_degrees(),
                ));
            }
            Some(Err(why)) => {
                ui.colored_label(ui.visuals().warn_fg_color, why);
            }
            None => {}
        }
        ui.horizontal_wrapped(|ui| {
            ui.colored_label(INLIER, "— inlier");
            ui.colored_label(OUTLIER, "— outlier (RANSAC)");
            ui.label("(lines: every outlier, and one inlier in every few)");
        });
        let gap = 8.0;
        let avail = ui.available_size();
        let (w0, h0) = (left.gray.width() as f32, left.gray.height() as f32);
        let (w1, h1) = (right.gray.width() as f32, right.gray.height() as f32);
        let half = ((avail.x - gap) / 2.0).max(40.0);
        let scale = (half / w0.max(w1)).min((avail.y - 4.0).max(60.0) / h0.max(h1));
        let size = Vec2::new(2.0 * w0.max(w1) * scale + gap, h0.max(h1) * scale);
        let (rect, _) = ui.allocate_exact_size(size, egui::Sense::hover());
        let rect_l = Rect::from_min_size(rect.min, Vec2::new(w0, h0) * scale);
        let rect_r = Rect::from_min_size(
            rect.min + Vec2::new(w0.max(w1) * scale + gap, 0.0),
            Vec2::new(w1, h1) * scale,
        );
        let painter = ui.painter_at(rect);
        let uv = Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0));
        for (texture, r) in self.textures.iter().zip([rect_l, rect_r]) {
            if let Some(t) = texture {
                painter.image(t.id(), r, uv, Color32::WHITE);
            }
        }
        if let Some(Ok(result)) = &self.result {
            let at = |r: Rect, p: &nalgebra::Vector2<f64>| {
                r.min + Vec2::new(p.x as f32 + 0.5, p.y as f32 + 0.5) * scale
            };
            // Every match gets its two circles; lines only for one match in
            // `stride` (at most about 80 lines), or the photos vanish under them.
            let matches = &result.matched.matches;
            let stride = matches.len().div_ceil(80).max(1);
            // Outliers first, so that the inliers are drawn over them.
            for pass_inliers in [false, true] {
                for (i, (m, inlier)) in matches.iter().zip(&result.estimate.inliers).enumerate() {
                    if *inlier != pass_inliers {
                        continue;
                    }
                    let colour = if *inlier { INLIER } else { OUTLIER };
                    let (a, b) = (at(rect_l, &m.left), at(rect_r, &m.right));
                    if i % stride == 0 || !*inlier {
                        painter.line_segment([a, b], Stroke::new(1.2, colour));
                    }
                    painter.circle_stroke(a, 2.5, Stroke::new(1.2, colour));
                    painter.circle_stroke(b, 2.5, Stroke::new(1.2, colour));
                }
            }
        }
    }

    /// The header's line while the photos are shown: their file names, the
    /// matches and RANSAC's inliers (or why there is no estimate).
    pub fn subtitle(&self) -> Option<String> {
        if !self.showing() {
            return None;
        }
        let (left, right) = (self.left.as_ref()?, self.right.as_ref()?);
        let names = format!("photos {} and {}", left.name, right.name);
        Some(match &self.result {
            Some(Ok(r)) => format!(
                "{names}: {} matches, {} inliers (five-point RANSAC)",
                r.matched.matches.len(),
                r.estimate.inlier_count
            ),
            Some(Err(why)) => format!("{names}: {why}"),
            None => names,
        })
    }

    /// The time bar's line while the photos are shown: RANSAC ran to its
    /// bound when they were loaded.
    pub fn phase(&self) -> Option<String> {
        match self.result.as_ref()? {
            Ok(r) => Some(format!(
                "the photos' RANSAC is done: {} samples (N = {})",
                r.estimate.iterations, r.estimate.bound
            )),
            Err(_) => Some("no estimate for the photos".to_owned()),
        }
    }

    /// For the UI tests.
    pub fn test_state(&self) -> serde_json::Value {
        let result = self.result.as_ref();
        serde_json::json!({
            "left": self.left.as_ref().map(|p| p.name.clone()),
            "right": self.right.as_ref().map(|p| p.name.clone()),
            "showing": self.showing(),
            "matches": result.and_then(|r| r.as_ref().ok()).map(|r| r.matched.matches.len()),
            "ambiguous": result.and_then(|r| r.as_ref().ok()).map(|r| r.matched.ambiguous),
            "inliers": result.and_then(|r| r.as_ref().ok()).map(|r| r.estimate.inlier_count),
            "rotation_deg": result.and_then(|r| r.as_ref().ok()).map(|r| rotation_angle(&r.estimate.rotation).to_degrees()),
            "motion": result.and_then(|r| r.as_ref().ok()).map(|r| match r.estimate.motion {
                Motion::General => "general",
                Motion::PureRotation => "pure-rotation",
            }),
            "parallax_px": result.and_then(|r| r.as_ref().ok()).map(|r| r.estimate.parallax_px),
            "error": result.and_then(|r| r.as_ref().err()).cloned(),
            "message": self.message.clone(),
        })
    }
}
