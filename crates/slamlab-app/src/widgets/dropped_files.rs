//! Files dropped on the window, read natively at once and in the browser
//! asynchronously, delivered to a lesson as one batch (a ROS map's YAML together
//! with its image).

use std::cell::RefCell;
use std::rc::Rc;

/// One dropped file: its name and its bytes, or why it could not be read.
pub type DroppedBytes = (String, Result<Vec<u8>, String>);

/// A batch's files that could be read (name and bytes, in order), and for each
/// one that could not, the note that says so.
pub fn sort_read(batch: Vec<DroppedBytes>) -> (Vec<(String, Vec<u8>)>, Vec<String>) {
    let mut read = Vec::new();
    let mut refused = Vec::new();
    for (name, bytes) in batch {
        match bytes {
            Ok(bytes) => read.push((name, bytes)),
            Err(why) => refused.push(format!("Could not read {name}: {why}")),
        }
    }
    (read, refused)
}

/// Takes the files dropped this frame for which `mine` holds out of the
/// frame's input (the rest stay there for the lesson), to read with
/// [`DropInbox::read`].
pub fn take_dropped(
    ctx: &egui::Context,
    mine: impl FnMut(&egui::DroppedFileHandle) -> bool,
) -> Vec<egui::DroppedFileHandle> {
    ctx.input_mut(|i| {
        let (taken, rest): (Vec<_>, Vec<_>) = std::mem::take(&mut i.raw.dropped_files)
            .into_iter()
            .partition(mine);
        i.raw.dropped_files = rest;
        taken
    })
}

/// Collects the files of one drop until all are read.
#[derive(Debug, Default)]
pub struct DropInbox {
    batch: Rc<RefCell<Vec<DroppedBytes>>>,
    expected: usize,
}

impl DropInbox {
    /// Starts reading what was dropped this frame (nothing if nothing was) and
    /// returns a complete batch once every file of the latest drop is read.
    pub fn poll(&mut self, ctx: &egui::Context) -> Option<Vec<DroppedBytes>> {
        let dropped = ctx.input(|i| i.raw.dropped_files.clone());
        self.read(ctx, dropped)
    }

    /// Like [`poll`](Self::poll), for files the caller took out of the frame's input
    /// itself (none this frame: just see whether the last batch is complete).
    #[cfg_attr(not(target_arch = "wasm32"), allow(unused_variables))]
    pub fn read(
        &mut self,
        ctx: &egui::Context,
        dropped: Vec<egui::DroppedFileHandle>,
    ) -> Option<Vec<DroppedBytes>> {
        if !dropped.is_empty() {
            self.batch = Rc::new(RefCell::new(Vec::new()));
            self.expected = dropped.len();
            for file in dropped {
                let name = file
                    .path()
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default();
                #[cfg(not(target_arch = "wasm32"))]
                self.batch.borrow_mut().push((name, file.bytes()));
                #[cfg(target_arch = "wasm32")]
                {
                    let batch = Rc::clone(&self.batch);
                    let ctx = ctx.clone();
                    wasm_bindgen_futures::spawn_local(async move {
                        let bytes = file.bytes_async().await;
                        batch.borrow_mut().push((name, bytes));
                        ctx.request_repaint();
                    });
                }
            }
        }
        if self.expected > 0 && self.batch.borrow().len() >= self.expected {
            self.expected = 0;
            return Some(std::mem::take(&mut *self.batch.borrow_mut()));
        }
        None
    }
}
