//! Exports from the app: the map or the whole window as PNG, every plot's data as
//! CSV, and the scenario as JSON (opened again by the file picker, by dropping it on
//! the window, or by `slamlab run --scenario FILE`).
//!
//! In the browser a file is a download; on the desktop a small window asks where to
//! save it (a path field, as the file picker has: a native dialog crate would pull
//! GTK or portal libraries in).

use crate::query::{self, APP_KEYS};
use slamlab_sim::io::scenario_file::ScenarioFile;
use std::sync::{Arc, Mutex};

/// One plotted series, for the CSV export.
#[derive(Clone, Debug, PartialEq)]
pub struct PlotSeries {
    /// The plot's title ("Robot position error").
    pub plot: String,
    /// The x axis ("time (s)").
    pub x_axis: String,
    /// The y axis ("error (m)").
    pub y_axis: String,
    /// The series' legend name ("EKF error").
    pub series: String,
    /// The points, unthinned.
    pub points: Vec<[f64; 2]>,
}

impl PlotSeries {
    /// A series of plot `plot` with axes `x_axis`, `y_axis`.
    pub fn new(
        plot: &str,
        x_axis: &str,
        y_axis: &str,
        series: impl Into<String>,
        points: Vec<[f64; 2]>,
    ) -> Self {
        Self {
            plot: plot.to_owned(),
            x_axis: x_axis.to_owned(),
            y_axis: y_axis.to_owned(),
            series: series.into(),
            points,
        }
    }
}

/// A CSV field, quoted when it holds a comma, a quote or a line break.
fn csv_field(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_owned()
    }
}

/// Every series as one long CSV table: `plot,x_axis,y_axis,series,x,y`, a row per
/// point, numbers in Rust's shortest round-trip form (NaN and infinities as written).
pub fn series_csv(series: &[PlotSeries]) -> String {
    let mut out = String::from("plot,x_axis,y_axis,series,x,y\n");
    for s in series {
        let head = format!(
            "{},{},{},{}",
            csv_field(&s.plot),
            csv_field(&s.x_axis),
            csv_field(&s.y_axis),
            csv_field(&s.series)
        );
        for [x, y] in &s.points {
            out.push_str(&format!("{head},{x},{y}\n"));
        }
    }
    out
}

/// The scenario file of a share link's query (`lesson=...&seed=7&tick=120`): the
/// lesson's pairs as `params`, the figure keys as `view`; `embed` is left out.
pub fn scenario_of_query(share_query: &str) -> ScenarioFile {
    let mut file = ScenarioFile::default();
    for (key, value) in query::decode_pairs(share_query.trim_start_matches('?')) {
        match key.as_str() {
            "" | "embed" => {}
            "lesson" => file.lesson = value,
            k if APP_KEYS.contains(&k) => file.view.push((key, value)),
            _ => file.params.push((key, value)),
        }
    }
    file
}

/// The query string that opens a scenario file (`embed` as asked).
pub fn query_of_scenario(file: &ScenarioFile, embed: bool) -> String {
    let pairs: Vec<(String, String)> = file.params.iter().chain(&file.view).cloned().collect();
    query::build(&file.lesson, &pairs, embed)
}

/// A rectangle of `image` (pixels; the whole image for `None`) as PNG bytes.
pub fn png_bytes(image: &egui::ColorImage, crop: Option<egui::Rect>) -> Result<Vec<u8>, String> {
    let [w, h] = image.size;
    let whole = egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(w as f32, h as f32));
    let area = crop.map_or(whole, |c| c.intersect(whole));
    let (x0, y0) = (area.min.x.round() as usize, area.min.y.round() as usize);
    let (x1, y1) = (
        (area.max.x.round() as usize).min(w),
        (area.max.y.round() as usize).min(h),
    );
    if x1 <= x0 || y1 <= y0 {
        return Err("the area to save is empty".to_owned());
    }
    let mut rgba = Vec::with_capacity((x1 - x0) * (y1 - y0) * 4);
    for y in y0..y1 {
        for pixel in &image.pixels[y * w + x0..y * w + x1] {
            rgba.extend_from_slice(&pixel.to_srgba_unmultiplied());
        }
    }
    let mut bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut bytes, (x1 - x0) as u32, (y1 - y0) as u32);
        encoder.set_color(png::ColorType::Rgba);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().map_err(|e| e.to_string())?;
        writer.write_image_data(&rgba).map_err(|e| e.to_string())?;
    }
    Ok(bytes)
}

/// What an export makes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExportKind {
    /// The map panel as PNG.
    MapPng,
    /// The whole window as PNG.
    WindowPng,
    /// Every plot's data as CSV.
    PlotsCsv,
    /// The scenario as JSON.
    ScenarioJson,
    /// Every trajectory of the run (TUM and CSV) and the landmarks, zipped.
    TrajectoriesZip,
    /// Homework: the report of the grade shown in the Assignment panel (JSON).
    GradeJson,
    /// Homework: a picture of the window with the lesson, the student's
    /// estimate and the grade (PNG).
    GradePng,
}

impl ExportKind {
    /// Every kind, with its name in the browser test hook.
    pub const ALL: [(Self, &'static str); 7] = [
        (Self::MapPng, "map-png"),
        (Self::WindowPng, "window-png"),
        (Self::PlotsCsv, "plots-csv"),
        (Self::ScenarioJson, "scenario-json"),
        (Self::TrajectoriesZip, "trajectories-zip"),
        (Self::GradeJson, "grade-json"),
        (Self::GradePng, "grade-png"),
    ];

    /// The kind called `name` (`map-png`, `window-png`, `plots-csv`, `scenario-json`,
    /// `trajectories-zip`, `grade-json`, `grade-png`).
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.iter().find(|(_, n)| *n == name).map(|(k, _)| *k)
    }
}

/// A file ready to save.
#[derive(Clone, Debug, PartialEq)]
pub struct ExportFile {
    /// The suggested file name.
    pub name: String,
    /// The MIME type (for the browser's download).
    pub mime: &'static str,
    /// The content.
    pub bytes: Vec<u8>,
}

/// How long a screenshot may take before the export gives up, seconds.
const SHOT_TIMEOUT_S: f32 = 10.0;

/// A screenshot asked of eframe, and where it lands.
#[derive(Debug)]
struct PendingShot {
    slot: Arc<Mutex<Option<Arc<egui::ColorImage>>>>,
    /// When it was asked for: a picture that never comes is given up after a while.
    asked: web_time::Instant,
    /// The area to keep, points (`None`: the whole window).
    crop: Option<egui::Rect>,
    name: String,
}

/// The exports in progress: a screenshot on its way, a file waiting for a path
/// (desktop), and what the last export did.
#[derive(Debug, Default)]
pub struct Exporter {
    shot: Option<PendingShot>,
    /// A file the desktop's save window is asking a path for, and the path typed.
    #[cfg_attr(target_arch = "wasm32", allow(dead_code))]
    saving: Option<(ExportFile, String)>,
    /// Files of the same export waiting for their save window (desktop).
    #[cfg(not(target_arch = "wasm32"))]
    queued: Vec<ExportFile>,
    /// What the last export did ("Saved …", or why it failed), shown in the menu bar.
    pub status: Option<String>,
    /// The last file handed to the browser or written (tests read it back).
    pub last: Option<ExportFile>,
}

impl Exporter {
    /// Asks eframe for a screenshot; the PNG (cropped to `crop`, points) is saved as
    /// `name` once it arrives ([`Exporter::ui`] watches for it).
    pub fn request_png(&mut self, ctx: &egui::Context, crop: Option<egui::Rect>, name: String) {
        let slot = Arc::new(Mutex::new(None));
        let landing = Arc::clone(&slot);
        let repaint = ctx.clone();
        ctx.send_viewport_cmd(egui::ViewportCommand::Screenshot(
            egui::ScreenshotCallback::new(move |image| {
                if let Ok(mut slot) = landing.lock() {
                    *slot = Some(image);
                }
                repaint.request_repaint();
            }),
        ));
        self.shot = Some(PendingShot {
            slot,
            asked: web_time::Instant::now(),
            crop,
            name,
        });
        self.status = Some("Taking the picture…".to_owned());
        ctx.request_repaint();
    }

    /// Is a picture asked for and not yet arrived?
    pub fn is_taking_picture(&self) -> bool {
        self.shot.is_some()
    }

    /// The path the desktop's save window will write to, while it is open.
    #[cfg(not(target_arch = "wasm32"))]
    pub fn save_path_mut(&mut self) -> Option<&mut String> {
        self.saving.as_mut().map(|(_, path)| path)
    }

    /// Saves `file`: a download in the browser, the save window on the desktop.
    pub fn save(&mut self, file: ExportFile) {
        #[cfg(target_arch = "wasm32")]
        {
            self.status = Some(match web::download(&file) {
                Ok(()) => format!("Downloaded {} ({})", file.name, size_text(file.bytes.len())),
                Err(e) => format!("{} could not be downloaded: {e}", file.name),
            });
            self.last = Some(file);
        }
        #[cfg(not(target_arch = "wasm32"))]
        {
            let path = std::env::current_dir()
                .map(|dir| dir.join(&file.name).to_string_lossy().into_owned())
                .unwrap_or_else(|_| file.name.clone());
            self.saving = Some((file, path));
        }
    }

    /// Saves several files that belong together (a ROS map's YAML and image):
    /// downloads in the browser; on the desktop, one save window after the
    /// other, each proposing the folder the one before was saved in.
    pub fn save_all(&mut self, files: Vec<ExportFile>) {
        #[cfg(target_arch = "wasm32")]
        {
            let mut done = Vec::new();
            for file in files {
                match web::download(&file) {
                    Ok(()) => done.push(file.name.clone()),
                    Err(e) => {
                        self.status = Some(format!("{} could not be downloaded: {e}", file.name));
                        return;
                    }
                }
                self.last = Some(file);
            }
            self.status = Some(format!("Downloaded {}", done.join(" and ")));
        }
        #[cfg(not(target_arch = "wasm32"))]
        {
            let mut files = files.into_iter();
            if let Some(first) = files.next() {
                self.queued = files.collect();
                self.save(first);
            }
        }
    }

    /// The files waiting for their save window after the one open now.
    #[cfg(not(target_arch = "wasm32"))]
    pub fn queued(&self) -> &[ExportFile] {
        &self.queued
    }

    /// Finishes a screenshot that arrived, and (desktop) shows the save window.
    pub fn ui(&mut self, ctx: &egui::Context) {
        let arrived = self
            .shot
            .as_ref()
            .and_then(|shot| shot.slot.lock().ok().and_then(|mut s| s.take()));
        if let Some(image) = arrived
            && let Some(shot) = self.shot.take()
        {
            let ppp = ctx.pixels_per_point();
            let crop = shot.crop.map(|r| {
                egui::Rect::from_min_max(
                    (r.min.to_vec2() * ppp).to_pos2(),
                    (r.max.to_vec2() * ppp).to_pos2(),
                )
            });
            match png_bytes(&image, crop) {
                Ok(bytes) => self.save(ExportFile {
                    name: shot.name,
                    mime: "image/png",
                    bytes,
                }),
                Err(e) => self.status = Some(format!("{} could not be made: {e}", shot.name)),
            }
        }
        // The picture arrives after a frame is painted; keep frames coming until it
        // does (an idle page paints nothing), and give up after a few seconds.
        if let Some(shot) = &self.shot {
            if shot.asked.elapsed().as_secs_f32() > SHOT_TIMEOUT_S {
                self.status = Some(format!(
                    "{} could not be made: the window gave no picture; try again",
                    shot.name
                ));
                self.shot = None;
            } else {
                ctx.request_repaint();
            }
        }
        #[cfg(not(target_arch = "wasm32"))]
        self.save_window_ui(ctx);
    }

    #[cfg(not(target_arch = "wasm32"))]
    fn save_window_ui(&mut self, ctx: &egui::Context) {
        let Some((file, path)) = &mut self.saving else {
            return;
        };
        let mut open = true;
        let mut done: Option<Result<String, String>> = None;
        egui::Window::new("Save file")
            .open(&mut open)
            .collapsible(false)
            .resizable(false)
            .constrain(true)
            .anchor(egui::Align2::CENTER_CENTER, egui::Vec2::ZERO)
            .show(ctx, |ui| {
                ui.label(format!("{} ({})", file.name, size_text(file.bytes.len())));
                let label = ui.label("Save as:");
                let field = ui
                    .add(egui::TextEdit::singleline(path).desired_width(360.0))
                    .labelled_by(label.id);
                let enter = field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
                ui.horizontal(|ui| {
                    if ui.button("Save").clicked() || enter {
                        done = Some(write_file(path.trim(), &file.bytes));
                    }
                    if ui.button("Cancel").clicked() {
                        done = Some(Err("Export cancelled".to_owned()));
                    }
                });
            });
        if !open {
            done = Some(Err("Export cancelled".to_owned()));
        }
        if let Some(result) = done
            && let Some((file, _)) = self.saving.take()
        {
            let folder = result.as_ref().ok().and_then(|path| {
                std::path::Path::new(path)
                    .parent()
                    .map(std::path::Path::to_path_buf)
            });
            self.status = Some(match result {
                Ok(path) => {
                    let text = format!("Saved {} to {path}", size_text(file.bytes.len()));
                    self.last = Some(file);
                    text
                }
                Err(e) => {
                    // A cancelled file cancels the rest of its export.
                    self.queued.clear();
                    e
                }
            });
            if !self.queued.is_empty() {
                let next = self.queued.remove(0);
                let path = folder
                    .unwrap_or_default()
                    .join(&next.name)
                    .to_string_lossy()
                    .into_owned();
                self.saving = Some((next, path));
            }
        }
    }
}

/// Writes `bytes` to `path`, or says why it could not.
#[cfg(not(target_arch = "wasm32"))]
fn write_file(path: &str, bytes: &[u8]) -> Result<String, String> {
    if path.is_empty() {
        return Err("Type a path to save to".to_owned());
    }
    std::fs::write(path, bytes)
        .map(|()| path.to_owned())
        .map_err(|e| format!("Could not save to {path}: {e}"))
}

/// "12.3 kB".
fn size_text(bytes: usize) -> String {
    if bytes < 1000 {
        format!("{bytes} bytes")
    } else {
        format!("{:.1} kB", bytes as f64 / 1000.0)
    }
}

#[cfg(target_arch = "wasm32")]
mod web {
    use super::ExportFile;
    use wasm_bindgen::JsCast as _;
    use wasm_bindgen::prelude::*;

    /// Hands `file` to the browser as a download (a Blob URL on a clicked link).
    pub fn download(file: &ExportFile) -> Result<(), String> {
        let err = |e: JsValue| format!("{e:?}");
        let window = web_sys::window().ok_or("no window")?;
        let document = window.document().ok_or("no document")?;
        let parts = js_sys::Array::of1(&js_sys::Uint8Array::from(file.bytes.as_slice()));
        let options = web_sys::BlobPropertyBag::new();
        options.set_type(file.mime);
        let blob =
            web_sys::Blob::new_with_u8_array_sequence_and_options(&parts, &options).map_err(err)?;
        let url = web_sys::Url::create_object_url_with_blob(&blob).map_err(err)?;
        let link = document
            .create_element("a")
            .map_err(err)?
            .dyn_into::<web_sys::HtmlAnchorElement>()
            .map_err(|_| "no link element".to_owned())?;
        link.set_href(&url);
        link.set_download(&file.name);
        link.click();
        // The browser has started the download; free the URL a moment later.
        let revoke = Closure::once_into_js(move || {
            let _ = web_sys::Url::revoke_object_url(&url);
        });
        let _ = window
            .set_timeout_with_callback_and_timeout_and_arguments_0(revoke.unchecked_ref(), 10_000);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_quotes_what_needs_it_and_keeps_every_point() {
        let series = [
            PlotSeries::new(
                "NEES",
                "time (s)",
                "NEES",
                "EKF NEES",
                vec![[0.1, 2.5], [0.2, f64::NAN]],
            ),
            PlotSeries::new("a, \"b\"", "x", "y", "s", vec![[1.0, 1e-9]]),
        ];
        let csv = series_csv(&series);
        assert_eq!(
            csv,
            "plot,x_axis,y_axis,series,x,y\n\
             NEES,time (s),NEES,EKF NEES,0.1,2.5\n\
             NEES,time (s),NEES,EKF NEES,0.2,NaN\n\
             \"a, \"\"b\"\"\",x,y,s,1,0.000000001\n"
        );
    }

    #[test]
    fn a_share_query_becomes_a_scenario_and_back() {
        let file = scenario_of_query("lesson=kidnap&seed=3&map=maps%2Foffice.yaml&tick=40&embed=1");
        assert_eq!(file.lesson, "kidnap");
        assert_eq!(
            file.params,
            vec![
                ("seed".to_owned(), "3".to_owned()),
                ("map".to_owned(), "maps/office.yaml".to_owned())
            ]
        );
        assert_eq!(file.view, vec![("tick".to_owned(), "40".to_owned())]);
        let again = ScenarioFile::parse(&file.to_json()).unwrap_or_default();
        assert_eq!(
            query_of_scenario(&again, false),
            "lesson=kidnap&seed=3&map=maps%2Foffice.yaml&tick=40"
        );
    }

    #[test]
    fn png_crops_and_encodes() {
        let mut image = egui::ColorImage::filled([4, 3], egui::Color32::WHITE);
        image.pixels[4 + 1] = egui::Color32::RED;
        let crop = egui::Rect::from_min_max(egui::pos2(1.0, 1.0), egui::pos2(3.0, 3.0));
        let bytes = png_bytes(&image, Some(crop)).unwrap_or_default();
        let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap_or(0)];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!((info.width, info.height), (2, 2));
        assert_eq!(&buf[..4], &[255, 0, 0, 255]);
        assert_eq!(&buf[4..8], &[255, 255, 255, 255]);
        let empty = egui::Rect::from_min_max(egui::pos2(9.0, 9.0), egui::pos2(12.0, 12.0));
        assert!(png_bytes(&image, Some(empty)).is_err());
    }
}
