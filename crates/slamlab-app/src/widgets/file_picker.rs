//! Opening files by a picker, natively and in the browser, without system
//! libraries: in the browser a hidden `<input type="file">` (the browser's own
//! dialog); natively a path field and an "Open" button (a native dialog crate
//! such as rfd would pull GTK or portal libraries in). Dropping a file on the
//! window ([`super::dropped_files::DropInbox`]) works in both.
//!
//! A picker takes one file, or several at once ([`FilePicker::multiple`]: a ROS
//! map's YAML together with its image). Natively the path field always names one
//! file, and [`FilePicker::folder`] says where it was, so that the caller can read
//! the files it names (the YAML's image) beside it.

use std::cell::RefCell;
use std::rc::Rc;

/// A picked file: its name and its bytes, or why it could not be read.
pub type PickedFile = (String, Result<Vec<u8>, String>);

/// A file picker; [`FilePicker::poll`] hands over what was picked.
#[derive(Debug, Default)]
pub struct FilePicker {
    picked: Rc<RefCell<Option<Vec<PickedFile>>>>,
    /// Does the browser's dialog let the student choose several files?
    #[cfg_attr(not(target_arch = "wasm32"), allow(dead_code))]
    multiple: bool,
    /// The path typed (native only).
    #[cfg(not(target_arch = "wasm32"))]
    path: String,
    /// The folder of the file picked last (native only).
    #[cfg(not(target_arch = "wasm32"))]
    folder: Option<std::path::PathBuf>,
}

impl FilePicker {
    /// A picker whose browser dialog takes several files at once.
    pub fn multiple() -> Self {
        Self {
            multiple: true,
            ..Self::default()
        }
    }

    /// The picker's widgets. `accept` lists the extensions offered
    /// (`".g2o,.graph,.toro,.txt"`); `max_bytes` refuses larger files unread; `hint`
    /// is the path field's placeholder (native).
    pub fn ui(
        &mut self,
        ui: &mut egui::Ui,
        label: &str,
        accept: &str,
        max_bytes: usize,
        hint: &str,
    ) {
        #[cfg(not(target_arch = "wasm32"))]
        {
            let _ = accept;
            // Wrapped: in a narrow panel the button goes below the field.
            ui.horizontal_wrapped(|ui| {
                let path_label = ui.label("path");
                let field = ui
                    .add(
                        egui::TextEdit::singleline(&mut self.path)
                            .hint_text(hint)
                            .desired_width(150.0),
                    )
                    .labelled_by(path_label.id);
                let enter = field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
                if ui
                    .button(label)
                    .on_hover_text("Read the file at this path")
                    .clicked()
                    || enter
                {
                    let path = self.path.trim();
                    self.folder = std::path::Path::new(path)
                        .parent()
                        .map(std::path::Path::to_path_buf);
                    *self.picked.borrow_mut() = Some(vec![read_native(path, max_bytes)]);
                }
            });
        }
        #[cfg(target_arch = "wasm32")]
        {
            let _ = hint;
            let hover = if self.multiple {
                "Choose the files with the browser's dialog (several at once)"
            } else {
                "Choose a file with the browser's dialog"
            };
            if ui.button(label).on_hover_text(hover).clicked() {
                web::open_dialog(
                    Rc::clone(&self.picked),
                    ui.ctx().clone(),
                    accept.to_owned(),
                    max_bytes,
                    self.multiple,
                );
            }
        }
    }

    /// The first file picked since the last poll.
    pub fn poll(&mut self) -> Option<PickedFile> {
        self.poll_all().and_then(|files| files.into_iter().next())
    }

    /// Every file picked since the last poll (several, from a [`multiple`](Self::multiple)
    /// picker in the browser).
    pub fn poll_all(&mut self) -> Option<Vec<PickedFile>> {
        self.picked.borrow_mut().take()
    }

    /// The folder of the file picked last (native), to read what it names beside it.
    #[cfg(not(target_arch = "wasm32"))]
    pub fn folder(&self) -> Option<&std::path::Path> {
        self.folder.as_deref()
    }
}

#[cfg(not(target_arch = "wasm32"))]
fn read_native(path: &str, max_bytes: usize) -> PickedFile {
    let name = std::path::Path::new(path)
        .file_name()
        .map_or_else(|| path.to_owned(), |n| n.to_string_lossy().into_owned());
    if path.is_empty() {
        return (name, Err("type a file's path first".to_owned()));
    }
    let bytes = std::fs::metadata(path)
        .map_err(|e| format!("cannot read {path}: {e}"))
        .and_then(|m| {
            if m.len() > max_bytes as u64 {
                Err(super::fetch::too_large(&name, m.len(), max_bytes as u64))
            } else {
                std::fs::read(path).map_err(|e| format!("cannot read {path}: {e}"))
            }
        });
    (name, bytes)
}

#[cfg(target_arch = "wasm32")]
mod web {
    use super::PickedFile;
    use std::cell::RefCell;
    use std::rc::Rc;
    use wasm_bindgen::JsCast as _;
    use wasm_bindgen::prelude::*;

    /// Opens the browser's file dialog; once every chosen file is read (as bytes),
    /// the batch lands in `picked`.
    pub fn open_dialog(
        picked: Rc<RefCell<Option<Vec<PickedFile>>>>,
        ctx: egui::Context,
        accept: String,
        max_bytes: usize,
        multiple: bool,
    ) {
        let Some(document) = web_sys::window().and_then(|w| w.document()) else {
            return;
        };
        let Ok(input) = document.create_element("input") else {
            return;
        };
        let Ok(input) = input.dyn_into::<web_sys::HtmlInputElement>() else {
            return;
        };
        input.set_type("file");
        input.set_multiple(multiple);
        input.set_accept(&accept);
        let reader_input = input.clone();
        let on_change = Closure::once_into_js(move || {
            let Some(files) = reader_input.files() else {
                return;
            };
            let files: Vec<web_sys::File> =
                (0..files.length()).filter_map(|i| files.get(i)).collect();
            wasm_bindgen_futures::spawn_local(async move {
                let mut batch = Vec::new();
                for file in files {
                    let name = file.name();
                    let size = file.size();
                    // Refused from its size, before a byte is read.
                    if size > max_bytes as f64 {
                        let why =
                            crate::widgets::fetch::too_large(&name, size as u64, max_bytes as u64);
                        batch.push((name, Err(why)));
                        continue;
                    }
                    let buffer = wasm_bindgen_futures::JsFuture::from(file.array_buffer()).await;
                    let bytes = match buffer {
                        Ok(value) => Ok(js_sys::Uint8Array::new(&value).to_vec()),
                        Err(_) => Err(format!("{name} could not be read")),
                    };
                    batch.push((name, bytes));
                }
                *picked.borrow_mut() = Some(batch);
                ctx.request_repaint();
            });
        });
        input.set_onchange(Some(on_change.unchecked_ref()));
        input.click();
    }
}
