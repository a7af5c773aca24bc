//! Browser entry point (wasm32 only).
//!
//! `web/index.html` loads the wasm-bindgen output (`pkg/slamlab_app.js`) and calls its
//! `init()`, which runs [`start`]. `start`:
//!
//! 1. creates the eframe [`eframe::WebRunner`] (which installs eframe's panic hook) and
//!    wraps that hook so that a panic also shows a red banner (`#panic`) in the page:
//!    a panic stops the egui app for good, and the user must see why;
//! 2. pipes `log` messages to the browser console ([`eframe::WebLogger`]);
//! 3. reads the page's query string (`?lesson=landmark-slam&seed=7&embed=1`) and starts
//!    [`SlamLabApp`] on `<canvas id="the_canvas_id">`;
//! 4. writes `running` or `error: ...` into `#status` (`panicked` after a panic);
//! 5. guards drops: a capture-phase `drop` listener on the page reads each dropped
//!    `File`'s size before eframe reads its bytes, and refuses the whole drop when a
//!    file is over its cap ([`crate::file_cap`]): the app then shows
//!    a notice naming the file and its size, and the lesson goes on.
//!
//! The browser tests (`web/tests/`) read the app's state through
//! [`slamlab_test_state`], [`slamlab_panicked`] and [`slamlab_panic_message`], start
//! exports with [`slamlab_test_export`], and check the panic banner with
//! [`slamlab_debug_panic`]. The page puts these exports on
//! `window.slamlab`, so they can also be called from the browser's developer console.

use std::cell::RefCell;

use wasm_bindgen::JsCast as _;
use wasm_bindgen::prelude::*;

use crate::SlamLabApp;

/// The id of the `<canvas>` in `web/index.html` that egui paints into.
const CANVAS_ID: &str = "the_canvas_id";

thread_local! {
    /// The running app, kept so that the exported test functions can reach it.
    static RUNNER: RefCell<Option<eframe::WebRunner>> = const { RefCell::new(None) };
    /// The open lesson's id (set every frame from the app), for the drop caps.
    static LESSON_ID: RefCell<String> = const { RefCell::new(String::new()) };
    /// Files of refused drops (name, size), for the app to say on its next frame.
    static REFUSED: RefCell<Vec<(String, u64)>> = const { RefCell::new(Vec::new()) };
    /// The app's context, to ask for a frame after a refused drop.
    static CONTEXT: RefCell<Option<egui::Context>> = const { RefCell::new(None) };
}

/// Listens for drops on the page before eframe does (capture phase): a drop
/// with a file over the cap is stopped there, unread, and remembered in
/// [`REFUSED`] for the app's notice.
fn install_drop_guard() -> Result<(), String> {
    let document = web_sys::window()
        .and_then(|w| w.document())
        .ok_or("no document")?;
    let on_drop = Closure::<dyn FnMut(web_sys::DragEvent)>::new(|event: web_sys::DragEvent| {
        let Some(files) = event.data_transfer().and_then(|d| d.files()) else {
            return;
        };
        let lesson = LESSON_ID.with(|l| l.borrow().clone());
        let too_large: Vec<(String, u64)> = (0..files.length())
            .filter_map(|i| files.get(i))
            .filter(|f| f.size() > crate::file_cap(&f.name(), &lesson) as f64)
            .map(|f| (f.name(), f.size() as u64))
            .collect();
        if too_large.is_empty() {
            return;
        }
        event.prevent_default();
        event.stop_immediate_propagation();
        REFUSED.with(|r| r.borrow_mut().extend(too_large));
        CONTEXT.with(|c| {
            if let Some(ctx) = c.borrow().as_ref() {
                ctx.request_repaint();
            }
        });
    });
    let options = web_sys::AddEventListenerOptions::new();
    options.set_capture(true);
    document
        .add_event_listener_with_callback_and_add_event_listener_options(
            "drop",
            on_drop.as_ref().unchecked_ref(),
            &options,
        )
        .map_err(|e| js_to_string(&e))?;
    // Listens as long as the page lives.
    on_drop.forget();
    Ok(())
}

/// Runs once when the wasm module is instantiated (wasm-bindgen's `start`).
#[wasm_bindgen(start)]
pub fn start() {
    // The runner installs eframe's panic hook (console.error with the call stack, and it
    // remembers the panic so the runner stops touching the poisoned app). Ours wraps it.
    let runner = eframe::WebRunner::new();
    install_panic_banner();

    // This fails only if a logger is already installed, and then that one is used.
    let _already_set = eframe::WebLogger::init(log::LevelFilter::Info);

    RUNNER.with(|cell| *cell.borrow_mut() = Some(runner.clone()));
    set_status("starting", "starting");
    if let Err(why) = install_drop_guard() {
        log::warn!("drops are not guarded by size: {why}");
    }
    wasm_bindgen_futures::spawn_local(async move {
        match start_app(&runner).await {
            Ok(()) => set_status("running", "running"),
            Err(message) => {
                log::error!("SLAM Lab could not start: {message}");
                set_status(&format!("error: {message}"), "error");
            }
        }
    });
}

/// Finds the canvas, reads the query string and starts the eframe runner.
async fn start_app(runner: &eframe::WebRunner) -> Result<(), String> {
    let window = web_sys::window().ok_or("no window object")?;
    let document = window.document().ok_or("no document")?;
    let search = window
        .location()
        .search()
        .map_err(|err| js_to_string(&err))?;
    let query = search.strip_prefix('?').unwrap_or(&search).to_owned();
    let canvas = document
        .get_element_by_id(CANVAS_ID)
        .ok_or_else(|| format!("the page has no <canvas id=\"{CANVAS_ID}\">"))?
        .dyn_into::<web_sys::HtmlCanvasElement>()
        .map_err(|_| format!("#{CANVAS_ID} is not a <canvas>"))?;
    runner
        .start(
            canvas,
            eframe::WebOptions::default(),
            Box::new(move |cc| {
                CONTEXT.with(|c| *c.borrow_mut() = Some(cc.egui_ctx.clone()));
                Ok(Box::new(WebApp {
                    inner: SlamLabApp::new(cc, &query),
                }))
            }),
        )
        .await
        .map_err(|err| js_to_string(&err))
}

/// The app's state as one line of JSON (`SlamLabApp::test_state_json`), or
/// `{"error":"..."}` when the app is not running (not started yet, or panicked).
#[wasm_bindgen]
pub fn slamlab_test_state() -> String {
    RUNNER.with(|cell| {
        let runner = cell.borrow();
        let Some(runner) = runner.as_ref() else {
            return r#"{"error":"not started"}"#.to_owned();
        };
        if runner.has_panicked() {
            return r#"{"error":"panicked"}"#.to_owned();
        }
        // `None` until the app is created, and while egui is painting a frame.
        match runner.app_mut::<WebApp>() {
            Some(app) => app.inner.test_state_json(),
            None => r#"{"error":"not running"}"#.to_owned(),
        }
    })
}

/// Runs `query`'s lesson headless for `ticks` ticks in this wasm module and returns
/// its test state (see `SlamLabApp::headless_state`), for comparing with the native
/// numbers.
#[wasm_bindgen]
pub fn slamlab_test_headless(query: &str, ticks: u32) -> String {
    SlamLabApp::headless_state(query, u64::from(ticks))
}

/// Opens `query`'s mapping or Cartographer lesson headless with the CARMEN log
/// `bytes` (named `name`), maps `ticks` scans and returns the test state (see
/// `SlamLabApp::headless_log_state`): the browser test times the Intel log with it.
#[wasm_bindgen]
pub fn slamlab_test_headless_log(query: &str, name: &str, bytes: &[u8], ticks: u32) -> String {
    SlamLabApp::headless_log_state(query, name, bytes, u64::from(ticks))
}

/// Opens a landmark data set of several files headless in the landmark lesson of
/// `query` and replays up to `ticks` ticks (see `SlamLabApp::headless_files_state`):
/// `names` holds the files' names one a line, `bytes` their contents one after the
/// other and `lengths` each one's length in bytes. Lengths that do not add up give an
/// error.
#[wasm_bindgen]
pub fn slamlab_test_headless_files(
    query: &str,
    names: &str,
    bytes: &[u8],
    lengths: &[u32],
    ticks: u32,
) -> String {
    let mut files = Vec::new();
    let mut at = 0usize;
    for (name, &length) in names.lines().zip(lengths) {
        let end = at.saturating_add(length as usize);
        let Some(contents) = bytes.get(at..end) else {
            return r#"{"error":"the lengths run past the bytes"}"#.to_owned();
        };
        files.push((name.to_owned(), contents.to_vec()));
        at = end;
    }
    SlamLabApp::headless_files_state(query, files, u64::from(ticks))
}

/// Starts an export as the File menu would (`map-png`, `window-png`, `plots-csv`,
/// `scenario-json`, `trajectories-zip`; with homework, `grade-json` and
/// `grade-png` as the Assignment panel's buttons); the browser downloads the file a frame or two later. False for
/// an unknown kind or when the app is not running.
#[wasm_bindgen]
pub fn slamlab_test_export(kind: &str) -> bool {
    let Some(kind) = crate::export::ExportKind::from_name(kind) else {
        return false;
    };
    RUNNER.with(|cell| {
        let runner = cell.borrow();
        let Some(runner) = runner.as_ref().filter(|r| !r.has_panicked()) else {
            return false;
        };
        match runner.app_mut::<WebApp>() {
            Some(mut app) => {
                app.inner.request_export(kind);
                true
            }
            None => false,
        }
    })
}

/// The lesson's own result as files, JSON `[{"name": …, "bytes": [..]}]`
/// (`SlamLabApp::own_result_files`: the mapping lesson's map as YAML and PGM,
/// the pose-graph lesson's graph as g2o), for the browser check that drops them
/// back on the page; `[]` when the app is not running.
#[wasm_bindgen]
pub fn slamlab_test_own_files() -> String {
    RUNNER.with(|cell| {
        let runner = cell.borrow();
        let Some(runner) = runner.as_ref().filter(|r| !r.has_panicked()) else {
            return "[]".to_owned();
        };
        match runner.app_mut::<WebApp>() {
            Some(app) => serde_json::Value::Array(
                app.inner
                    .own_result_files()
                    .into_iter()
                    .map(|(name, bytes)| serde_json::json!({ "name": name, "bytes": bytes }))
                    .collect(),
            )
            .to_string(),
            None => "[]".to_owned(),
        }
    })
}

/// Has the app panicked (and therefore stopped)?
#[wasm_bindgen]
pub fn slamlab_panicked() -> bool {
    RUNNER.with(|cell| {
        cell.borrow()
            .as_ref()
            .is_some_and(eframe::WebRunner::has_panicked)
    })
}

/// The panic message, if the app has panicked.
#[wasm_bindgen]
pub fn slamlab_panic_message() -> Option<String> {
    RUNNER.with(|cell| {
        let runner = cell.borrow();
        runner
            .as_ref()?
            .panic_summary()
            .map(|summary| summary.message())
    })
}

/// Panics on purpose, with `message`: the browser tests use it to check that a panic is
/// shown in the page (the `#panic` banner) and stops the app cleanly.
#[wasm_bindgen]
#[expect(clippy::panic, reason = "the point of this function is to panic")]
pub fn slamlab_debug_panic(message: &str) {
    panic!("{message}");
}

/// Wraps the current panic hook (eframe's) so that a panic is also shown in the page.
fn install_panic_banner() {
    let previous_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        previous_hook(info);
        let message = info.to_string();
        log::error!("SLAM Lab stopped after a panic: {message}");
        show_panic_banner(&message);
        set_status("panicked", "panicked");
    }));
}

/// Shows the panic in the `#panic` element of the page (or in an alert if there is none).
fn show_panic_banner(message: &str) {
    let Some(window) = web_sys::window() else {
        return;
    };
    let text = format!(
        "SLAM Lab stopped because of an internal error:\n\n{message}\n\n\
         Reload the page to start again. If it happens again, please report it \
         together with the page address."
    );
    let banner = window
        .document()
        .and_then(|document| document.get_element_by_id("panic"))
        .and_then(|element| element.dyn_into::<web_sys::HtmlElement>().ok());
    match banner {
        Some(banner) => {
            banner.set_inner_text(&text);
            banner.set_hidden(false);
        }
        None => {
            let _ignored = window.alert_with_message(&text);
        }
    }
}

/// Writes `text` into `#status` and `state` into its `data-state` attribute (the page's
/// CSS hides the status line once it is `running`).
fn set_status(text: &str, state: &str) {
    let status = web_sys::window()
        .and_then(|window| window.document())
        .and_then(|document| document.get_element_by_id("status"))
        .and_then(|element| element.dyn_into::<web_sys::HtmlElement>().ok());
    if let Some(status) = status {
        status.set_inner_text(text);
        let _ignored = status.set_attribute("data-state", state);
    }
}

/// Shows `query` in the page's address without reloading (the history entry is
/// replaced, not added): after a switch of lessons a reload opens the lesson on
/// screen, and the address names it.
fn replace_address(query: &str) {
    let Some(window) = web_sys::window() else {
        return;
    };
    let location = window.location();
    let path = location.pathname().unwrap_or_default();
    let hash = location.hash().unwrap_or_default();
    let url = format!("{path}?{query}{hash}");
    if let Ok(history) = window.history()
        && let Err(err) = history.replace_state_with_url(&JsValue::NULL, "", Some(&url))
    {
        log::warn!(
            "could not show the lesson in the address: {}",
            js_to_string(&err)
        );
    }
}

/// A JavaScript error as text.
fn js_to_string(value: &JsValue) -> String {
    value.as_string().unwrap_or_else(|| format!("{value:?}"))
}

/// Wraps [`SlamLabApp`] so that [`eframe::WebRunner::app_mut`] can reach it: eframe needs
/// `App::as_any_mut` for that, and the wrapper provides it. Every other `App` method is
/// passed through, so the app behaves exactly as it does natively.
struct WebApp {
    inner: SlamLabApp,
}

impl eframe::App for WebApp {
    fn logic(&mut self, ctx: &egui::Context, frame: &mut eframe::Frame) {
        self.inner.logic(ctx, frame);
    }

    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        LESSON_ID.with(|l| {
            let id = self.inner.lesson_id();
            if *l.borrow() != id {
                *l.borrow_mut() = id.to_owned();
            }
        });
        for (name, size) in REFUSED.with(|r| std::mem::take(&mut *r.borrow_mut())) {
            self.inner.refuse_dropped(&name, size);
        }
        self.inner.ui(ui, frame);
        if let Some(query) = self.inner.take_address_change() {
            replace_address(&query);
        }
    }

    fn as_any_mut(&mut self) -> Option<&mut dyn std::any::Any> {
        Some(&mut *self)
    }

    fn save(&mut self, storage: &mut dyn eframe::Storage) {
        self.inner.save(storage);
    }

    fn auto_save_interval(&self) -> std::time::Duration {
        self.inner.auto_save_interval()
    }

    fn clear_color(&self, visuals: &egui::Visuals) -> [f32; 4] {
        self.inner.clear_color(visuals)
    }

    fn persist_egui_memory(&self) -> bool {
        self.inner.persist_egui_memory()
    }

    fn raw_input_hook(&mut self, ctx: &egui::Context, raw_input: &mut egui::RawInput) {
        self.inner.raw_input_hook(ctx, raw_input);
    }
}
