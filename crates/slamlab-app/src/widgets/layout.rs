//! The layout every lesson shares: plots along the bottom, parameters on the
//! left, the explanation on the right, the map in the middle; each side panel
//! collapsible and resizable.
//!
//! The map always keeps the room: the plots take at most a share of the height,
//! and below [`NARROW_WIDTH`] the side panels become drawers that slide over the
//! map (one at a time, closed until asked for) instead of squeezing it. The map's
//! rectangle is kept for the shell ([`map_rect`]) and the browser tests.

use crate::panels::PanelVisibility;

/// Below this window width (points) the side panels are drawers over the map.
pub const NARROW_WIDTH: f32 = 1000.0;

/// The most of the height below the top bars that the plots may take.
pub const PLOTS_MAX_SHARE: f32 = 0.4;

/// Below this width or this height (points, below the top bars) the plots leave the
/// bottom of the window for a drawer of their own, closed until asked for: a phone
/// in landscape or a small iframe keeps the whole height for the map.
pub const TINY_WIDTH: f32 = 600.0;
/// See [`TINY_WIDTH`].
pub const TINY_HEIGHT: f32 = 400.0;

/// A lesson's four areas.
pub trait LessonPanels {
    /// The plots (bottom).
    fn plots_ui(&mut self, ui: &mut egui::Ui);
    /// The parameter panel (left).
    fn parameters_ui(&mut self, ui: &mut egui::Ui);
    /// The explanation panel (right).
    fn explanation_ui(&mut self, ui: &mut egui::Ui);
    /// The map and its toolbar (centre).
    fn map_ui(&mut self, ui: &mut egui::Ui);
}

/// Is the window too narrow for side panels beside the map?
pub fn is_narrow(ctx: &egui::Context) -> bool {
    ctx.content_rect().width() < NARROW_WIDTH
}

fn map_rect_id() -> egui::Id {
    egui::Id::unique("slamlab_map_rect")
}

fn open_drawer_id(id: &str) -> egui::Id {
    egui::Id::unique(("slamlab_open_drawer", id))
}

/// The map's (central panel's) rectangle in the last frame, points.
pub fn map_rect(ctx: &egui::Context) -> Option<egui::Rect> {
    ctx.data(|d| d.get_temp(map_rect_id()))
}

/// The widest stretch of `span` that none of `covered` covers, as (left,
/// right); `span` itself when every stretch is narrower than `min_width` (the
/// box then lies under a window rather than shrink to nothing). A span that
/// is itself narrower than `min_width` (a tiny map, or a NaN edge) is returned
/// as it is.
pub fn widest_gap(span: egui::Rangef, covered: &[egui::Rangef], min_width: f32) -> (f32, f32) {
    if !(span.max - span.min >= min_width) {
        return (span.min, span.max);
    }
    let mut edges: Vec<f32> = vec![span.min, span.max];
    for c in covered {
        // max/min rather than clamp: a NaN edge stays NaN and sorts away
        // instead of panicking.
        edges.extend([c.min - 8.0, c.max + 8.0].map(|x| x.max(span.min).min(span.max)));
    }
    edges.sort_by(f32::total_cmp);
    edges
        .windows(2)
        .map(|w| (w[0], w[1]))
        .filter(|(a, b)| {
            let middle = 0.5 * (a + b);
            !covered
                .iter()
                .any(|c| c.min - 8.0 <= middle && middle <= c.max + 8.0)
        })
        .max_by(|x, y| (x.1 - x.0).total_cmp(&(y.1 - y.0)))
        .filter(|(a, b)| b - a >= min_width)
        .unwrap_or((span.min, span.max))
}

/// Lays out `lesson`'s areas; `id` keeps each lesson's panel sizes apart.
pub fn lesson_panels_ui(
    lesson: &mut (impl LessonPanels + ?Sized),
    ui: &mut egui::Ui,
    panels: &mut PanelVisibility,
    compact: bool,
    id: &str,
) {
    let area = ui.available_rect_before_wrap();
    let narrow = is_narrow(ui.ctx());
    // An embed's plot row shows fewer plots, each tall enough to read.
    crate::widgets::plots::set_embed_layout(ui.ctx(), compact);
    let tiny = area.width() < TINY_WIDTH || area.height() < TINY_HEIGHT;
    if tiny {
        // The plots become a drawer, closed when the window first gets this small.
        let ctx = ui.ctx().clone();
        let was_tiny_id = egui::Id::unique(("slamlab_was_tiny", id));
        if !ctx.data(|d| d.get_temp::<bool>(was_tiny_id).unwrap_or(false)) {
            panels.plots = false;
        }
        ctx.data_mut(|d| d.insert_temp(was_tiny_id, true));
        let map = egui::CentralPanel::default().show(ui, |ui| lesson.map_ui(ui));
        let map = map.response.rect;
        ctx.data_mut(|d| d.insert_temp(map_rect_id(), map));
        let space = area.with_min_y(map.top());
        drawers_ui(lesson, ui, panels, id, space);
        if panels.plots {
            plots_drawer_ui(lesson, &ctx, panels, id, space);
        }
        return;
    }
    ui.ctx()
        .data_mut(|d| d.insert_temp(egui::Id::unique(("slamlab_was_tiny", id)), false));
    // The plots shrink with the window so that the map keeps at least 60% of it.
    let plots_max = (PLOTS_MAX_SHARE * area.height()).max(60.0);
    // An embed's row holds two plots (`plots::EMBED_PLOTS`): a little taller than
    // the app's share, so that each is at least 90 points tall at 900 x 600.
    let (plot_height, share): (f32, f32) = if compact { (185.0, 0.34) } else { (230.0, 0.3) };
    let plot_height = plot_height.min(share * area.height()).max(60.0);
    egui::Panel::bottom(format!("{id}_plots"))
        .resizable(true)
        .default_size(plot_height)
        .size_range(plots_max.min(120.0).min(plot_height)..=plots_max)
        .show_collapsible(ui, &mut panels.plots, |ui| {
            lesson.plots_ui(ui);
            // Fill the panel to its bottom edge, whatever the plots used.
            ui.expand_to_include_rect(ui.max_rect());
        });
    if narrow {
        let map = egui::CentralPanel::default().show(ui, |ui| lesson.map_ui(ui));
        let map = map.response.rect;
        ui.ctx().data_mut(|d| d.insert_temp(map_rect_id(), map));
        drawers_ui(lesson, ui, panels, id, area.with_min_y(map.top()));
        return;
    }
    // Side panels beside the map, each at most a quarter of the width.
    let side = |default: f32| default.min(0.24 * area.width()).max(180.0);
    egui::Panel::left(format!("{id}_parameters"))
        .resizable(true)
        .default_size(side(300.0))
        .size_range(180.0..=480.0_f32.min(0.35 * area.width()).max(180.0))
        .show_collapsible(ui, &mut panels.parameters, |ui| {
            // Scrolls sideways rather than widening the panel over the map.
            egui::ScrollArea::both()
                .id_salt(format!("{id}_parameters_scroll"))
                .show(ui, |ui| lesson.parameters_ui(ui));
        });
    egui::Panel::right(format!("{id}_explanation"))
        .resizable(true)
        .default_size(side(330.0))
        .size_range(180.0..=520.0_f32.min(0.35 * area.width()).max(180.0))
        .show_collapsible(ui, &mut panels.explanation, |ui| {
            // Scrolls sideways rather than widening the panel over the map.
            egui::ScrollArea::both()
                .id_salt(format!("{id}_explanation_scroll"))
                .show(ui, |ui| lesson.explanation_ui(ui));
        });
    let map = egui::CentralPanel::default().show(ui, |ui| lesson.map_ui(ui));
    ui.ctx()
        .data_mut(|d| d.insert_temp(map_rect_id(), map.response.rect));
}

/// The side panels of a narrow window: drawers over the map (and the plots), the
/// parameters from the left, the explanation from the right, one at a time.
fn drawers_ui(
    lesson: &mut (impl LessonPanels + ?Sized),
    ui: &mut egui::Ui,
    panels: &mut PanelVisibility,
    id: &str,
    space: egui::Rect,
) {
    // Opening one drawer closes the other.
    let ctx = ui.ctx().clone();
    let before: (bool, bool) = ctx.data(|d| d.get_temp(open_drawer_id(id)).unwrap_or_default());
    if panels.parameters && panels.explanation {
        if before.0 {
            panels.parameters = false;
        } else {
            panels.explanation = false;
        }
    }
    ctx.data_mut(|d| {
        d.insert_temp(open_drawer_id(id), (panels.parameters, panels.explanation));
    });
    let width = 340.0_f32.min(0.88 * space.width());
    let drawers = [
        (panels.parameters, true, "Parameters"),
        (panels.explanation, false, "Explanation"),
    ];
    for (open, left, title) in drawers {
        if !open {
            continue;
        }
        let x = if left {
            space.left()
        } else {
            space.right() - width
        };
        let rect = egui::Rect::from_min_size(
            egui::pos2(x, space.top()),
            egui::vec2(width, space.height()),
        );
        let close = drawer_ui(
            &ctx,
            egui::Id::unique((id, title, "drawer")),
            rect,
            title,
            |ui| {
                egui::ScrollArea::vertical()
                    .id_salt(format!("{id}_{title}_drawer_scroll"))
                    .auto_shrink([false, false])
                    .show(ui, |ui| {
                        if left {
                            lesson.parameters_ui(ui);
                        } else {
                            lesson.explanation_ui(ui);
                        }
                    });
            },
        );
        if close {
            if left {
                panels.parameters = false;
            } else {
                panels.explanation = false;
            }
        }
    }
}

/// The plots of a tiny window: a drawer over the lower part of the map, with a
/// Close button.
fn plots_drawer_ui(
    lesson: &mut (impl LessonPanels + ?Sized),
    ctx: &egui::Context,
    panels: &mut PanelVisibility,
    id: &str,
    space: egui::Rect,
) {
    let height = (0.6 * space.height()).max(120.0).min(space.height());
    let rect = egui::Rect::from_min_size(
        egui::pos2(space.left(), space.bottom() - height),
        egui::vec2(space.width(), height),
    );
    let close = drawer_ui(
        ctx,
        egui::Id::unique((id, "plots drawer")),
        rect,
        "Plots",
        |ui| {
            // Side by side, scrolled sideways: each plot keeps a readable width.
            egui::ScrollArea::horizontal()
                .id_salt(format!("{id}_plots_drawer_scroll"))
                .show(ui, |ui| {
                    ui.set_min_width(900.0);
                    ui.set_height(ui.available_height());
                    lesson.plots_ui(ui);
                });
        },
    );
    if close {
        panels.plots = false;
    }
}

/// A drawer at `rect` over the map: a title row with a Close button, then
/// `add_contents`. Returns whether Close was clicked.
fn drawer_ui(
    ctx: &egui::Context,
    id: egui::Id,
    rect: egui::Rect,
    title: &str,
    add_contents: impl FnOnce(&mut egui::Ui),
) -> bool {
    let mut close = false;
    egui::Area::new(id)
        .order(egui::Order::Middle)
        .fixed_pos(rect.min)
        .constrain(false)
        .show(ctx, |ui| {
            egui::Frame::side_top_panel(ui.style())
                .stroke(ui.visuals().window_stroke())
                .shadow(ui.visuals().popup_shadow)
                .show(ui, |ui| {
                    let inner = rect.shrink2(egui::vec2(8.0, 2.0));
                    ui.set_min_size(inner.size());
                    ui.set_max_size(inner.size());
                    ui.horizontal(|ui| {
                        ui.label(egui::RichText::new(title).strong());
                        ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
                            close = ui
                                .button("Close")
                                .on_hover_text("Close this drawer and show the map")
                                .clicked();
                        });
                    });
                    ui.separator();
                    add_contents(ui);
                });
        });
    close
}

#[cfg(test)]
mod tests {
    use super::widest_gap;
    use egui::Rangef;

    /// The notices box's stretch: the whole span without windows, the part
    /// left of a corner window (8 points clear of it), the wider side of a
    /// window in the middle, and the whole span when no side is wide enough.
    #[test]
    fn the_widest_gap_keeps_clear_of_the_windows() {
        let span = Rangef::new(8.0, 792.0);
        assert_eq!(widest_gap(span, &[], 120.0), (8.0, 792.0));
        let corner = Rangef::new(456.0, 800.0);
        assert_eq!(widest_gap(span, &[corner], 120.0), (8.0, 448.0));
        let middle = Rangef::new(200.0, 400.0);
        assert_eq!(widest_gap(span, &[middle], 120.0), (408.0, 792.0));
        let wide = Rangef::new(60.0, 740.0);
        assert_eq!(widest_gap(span, &[wide], 120.0), (8.0, 792.0));
    }

    /// A map narrower than the box (its span shrunk past empty) or with a NaN
    /// edge gives its span back rather than panic, with a window over it.
    #[test]
    fn a_tiny_or_broken_span_is_returned_as_it_is() {
        let corner = Rangef::new(0.0, 300.0);
        assert_eq!(
            widest_gap(Rangef::new(8.0, 4.0), &[corner], 120.0),
            (8.0, 4.0)
        );
        assert_eq!(
            widest_gap(Rangef::new(8.0, 60.0), &[corner], 120.0),
            (8.0, 60.0)
        );
        let (left, right) = widest_gap(Rangef::new(8.0, f32::NAN), &[corner], 120.0);
        assert_eq!(left, 8.0);
        assert!(right.is_nan());
        let nan_window = Rangef::new(f32::NAN, 300.0);
        let (left, right) = widest_gap(Rangef::new(8.0, 792.0), &[nan_window], 120.0);
        assert!(left >= 8.0 && right <= 792.0 && right - left >= 120.0);
    }
}
