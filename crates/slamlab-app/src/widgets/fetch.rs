//! Reads a file named in the URL: in the browser an HTTP request relative to
//! the page (an instructor hosts a map beside the site), on the desktop a path
//! relative to the working directory. Either way the result arrives in a later
//! frame through [`Fetch::poll`].

use std::cell::RefCell;
use std::rc::Rc;

/// The bytes of a requested file, or why it could not be read.
pub type Fetched = Result<Vec<u8>, String>;

/// One request under way.
#[derive(Debug, Default)]
pub struct Fetch {
    slot: Rc<RefCell<Option<Fetched>>>,
    pending: bool,
}

/// Largest file read, bytes (a map's image of 50 million cells fits).
pub const MAX_FETCH_BYTES: usize = 64 << 20;

/// Why a file of `size` bytes is refused unread: the one message of every
/// size cap (a drop, the file picker, a file named in the URL).
pub fn too_large(name: &str, size: u64, max_bytes: u64) -> String {
    format!("{name} has {size} bytes, more than the {max_bytes} bytes SLAM Lab reads")
}

impl Fetch {
    /// Starts reading `location` (a URL relative to the page in the browser, a
    /// path on the desktop).
    pub fn start(location: &str, ctx: &egui::Context) -> Self {
        let slot: Rc<RefCell<Option<Fetched>>> = Rc::new(RefCell::new(None));
        #[cfg(not(target_arch = "wasm32"))]
        {
            let _ = ctx;
            let read = std::fs::metadata(location)
                .map_err(|e| format!("cannot read {location}: {e}"))
                .and_then(|meta| {
                    if meta.len() > MAX_FETCH_BYTES as u64 {
                        Err(too_large(location, meta.len(), MAX_FETCH_BYTES as u64))
                    } else {
                        std::fs::read(location).map_err(|e| format!("cannot read {location}: {e}"))
                    }
                });
            *slot.borrow_mut() = Some(read);
        }
        #[cfg(target_arch = "wasm32")]
        {
            let target = Rc::clone(&slot);
            let ctx = ctx.clone();
            let location = location.to_owned();
            wasm_bindgen_futures::spawn_local(async move {
                let result = fetch_web(&location).await;
                *target.borrow_mut() = Some(result);
                ctx.request_repaint();
            });
        }
        Self {
            slot,
            pending: true,
        }
    }

    /// The result once it has arrived (once).
    pub fn poll(&mut self) -> Option<Fetched> {
        if !self.pending {
            return None;
        }
        let result = self.slot.borrow_mut().take();
        if result.is_some() {
            self.pending = false;
        }
        result
    }

    /// Is a request under way?
    pub fn is_pending(&self) -> bool {
        self.pending
    }
}

/// A file named in a lesson's link (`log=`, `reference=`), read after the first
/// frame (the one that has the context): its location, and the read once it has
/// started.
#[derive(Debug)]
pub struct LinkedFile {
    location: String,
    fetch: Option<Fetch>,
}

impl LinkedFile {
    /// A file at `location`, not read yet.
    pub fn new(location: String) -> Self {
        Self {
            location,
            fetch: None,
        }
    }

    /// Where the file is, as the link gave it.
    pub fn location(&self) -> &str {
        &self.location
    }

    /// Moves the read of `slot`'s file along: the first call starts it, later
    /// calls poll it. Once the bytes (or why there are none) have arrived, the
    /// slot is emptied and the location comes back with them.
    pub fn poll(slot: &mut Option<LinkedFile>, ctx: &egui::Context) -> Option<(String, Fetched)> {
        let file = slot.as_mut()?;
        let Some(fetch) = file.fetch.as_mut() else {
            file.fetch = Some(Fetch::start(&file.location, ctx));
            return None;
        };
        let result = fetch.poll()?;
        slot.take().map(|file| (file.location, result))
    }
}

/// A location's file name: what follows its last `/`.
pub fn file_name(location: &str) -> &str {
    location.rsplit('/').next().unwrap_or(location)
}

/// `location` resolved against the directory of `base` (`maps/lab.yaml` and
/// `lab.pgm` give `maps/lab.pgm`); an absolute URL or path stays as it is.
pub fn relative_to(base: &str, location: &str) -> String {
    if location.starts_with('/') || location.contains("://") {
        return location.to_owned();
    }
    match base.rfind('/') {
        Some(slash) => format!("{}{location}", &base[..=slash]),
        None => location.to_owned(),
    }
}

#[cfg(target_arch = "wasm32")]
async fn fetch_web(location: &str) -> Fetched {
    use wasm_bindgen::JsCast as _;
    use wasm_bindgen_futures::JsFuture;
    let describe = |e: wasm_bindgen::JsValue| {
        e.as_string()
            .or_else(|| {
                e.dyn_ref::<js_sys::Error>()
                    .map(|err| String::from(err.message()))
            })
            .unwrap_or_else(|| {
                "the request failed (another host without CORS, or offline)".to_owned()
            })
    };
    let window = web_sys::window().ok_or("no browser window")?;
    let response = JsFuture::from(window.fetch_with_str(location))
        .await
        .map_err(|e| format!("{location}: {}", describe(e)))?;
    let response: web_sys::Response = response
        .dyn_into()
        .map_err(|_| format!("{location}: not an HTTP response"))?;
    if !response.ok() {
        return Err(format!(
            "{location}: the server answered {} {}",
            response.status(),
            response.status_text()
        ));
    }
    // Refused before the body is read when the server says how long it is
    // (else after, below).
    if let Some(length) = response
        .headers()
        .get("content-length")
        .ok()
        .flatten()
        .and_then(|l| l.trim().parse::<u64>().ok())
        && length > MAX_FETCH_BYTES as u64
    {
        return Err(too_large(location, length, MAX_FETCH_BYTES as u64));
    }
    let buffer = response
        .array_buffer()
        .map_err(|e| format!("{location}: {}", describe(e)))?;
    let buffer = JsFuture::from(buffer)
        .await
        .map_err(|e| format!("{location}: {}", describe(e)))?;
    let bytes = js_sys::Uint8Array::new(&buffer);
    if bytes.length() as usize > MAX_FETCH_BYTES {
        return Err(too_large(
            location,
            u64::from(bytes.length()),
            MAX_FETCH_BYTES as u64,
        ));
    }
    Ok(bytes.to_vec())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_locations_resolve_against_the_yaml() {
        assert_eq!(relative_to("maps/lab.yaml", "lab.pgm"), "maps/lab.pgm");
        assert_eq!(relative_to("lab.yaml", "lab.pgm"), "lab.pgm");
        assert_eq!(
            relative_to("a/b/lab.yaml", "../img/lab.png"),
            "a/b/../img/lab.png"
        );
        assert_eq!(relative_to("maps/lab.yaml", "/srv/lab.pgm"), "/srv/lab.pgm");
        assert_eq!(
            relative_to("maps/lab.yaml", "https://example.org/lab.pgm"),
            "https://example.org/lab.pgm"
        );
    }

    /// A file over the cap is refused from its size (a sparse file: nothing
    /// is read), with the message every cap gives.
    #[test]
    fn a_file_over_the_cap_is_refused_unread() {
        let path = std::env::temp_dir().join(format!("slamlab-big-{}.tum", std::process::id()));
        let file = std::fs::File::create(&path).unwrap();
        file.set_len(65 << 20).unwrap();
        let location = path.to_string_lossy().into_owned();
        let mut fetch = Fetch::start(&location, &egui::Context::default());
        let result = fetch.poll();
        let _ = std::fs::remove_file(&path);
        assert_eq!(
            result,
            Some(Err(format!(
                "{location} has 68157440 bytes, more than the 67108864 bytes SLAM Lab reads"
            )))
        );
    }

    #[test]
    fn a_linked_file_starts_then_arrives_once_and_empties_its_slot() {
        let ctx = egui::Context::default();
        let mut slot = Some(LinkedFile::new("no/such/log.clf".to_owned()));
        assert!(LinkedFile::poll(&mut slot, &ctx).is_none(), "started");
        assert_eq!(
            slot.as_ref().map(LinkedFile::location),
            Some("no/such/log.clf")
        );
        let arrived = LinkedFile::poll(&mut slot, &ctx);
        assert!(
            matches!(&arrived, Some((at, Err(m))) if at == "no/such/log.clf" && m.contains(at)),
            "{arrived:?}"
        );
        assert!(slot.is_none());
        assert!(LinkedFile::poll(&mut slot, &ctx).is_none());
        assert_eq!(file_name("logs/intel.clf"), "intel.clf");
        assert_eq!(file_name("intel.clf"), "intel.clf");
    }

    #[test]
    fn a_missing_file_is_a_message() {
        let ctx = egui::Context::default();
        let mut fetch = Fetch::start("no/such/map.yaml", &ctx);
        let result = fetch.poll();
        assert!(
            matches!(&result, Some(Err(m)) if m.contains("no/such/map.yaml")),
            "{result:?}"
        );
        assert!(fetch.poll().is_none(), "delivered once");
    }
}
