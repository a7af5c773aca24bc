//! A parameter panel built from a scenario's parameter table: a slider for a
//! number, a drag value for a count, a combo box for a word. Every widget writes
//! through [`slamlab_sim::params::set`] with the parameter's URL name, so the
//! panel, the URL and the command line share one vocabulary and one validation.

use crate::palette;
use slamlab_sim::params::{self, ParamKind, Scenario};
use std::collections::BTreeMap;

/// The pending scenario of a lesson's parameter panel (applied on reset) and the
/// message about the last value typed for each parameter.
#[derive(Clone, Debug, Default)]
pub struct PendingParams<S> {
    /// The scenario being edited.
    pub scenario: S,
    /// Problems with the values typed, by parameter name.
    pub issues: BTreeMap<String, String>,
}

impl<S: Scenario> PendingParams<S> {
    /// Starts editing `scenario`.
    pub fn new(scenario: S) -> Self {
        Self {
            scenario,
            issues: BTreeMap::new(),
        }
    }

    /// Sets one parameter from text, keeping the message about it (if any).
    pub fn set(&mut self, name: &str, value: &str) -> Option<params::ParamIssue> {
        let issue = params::set(&mut self.scenario, name, value);
        match &issue {
            Some(issue) => {
                self.issues.insert(name.to_owned(), issue.to_string());
            }
            None => {
                self.issues.remove(name);
            }
        }
        issue
    }

    /// Does the pending scenario differ from `running` in any parameter?
    pub fn differs_from(&self, running: &S) -> bool {
        params::to_pairs(&self.scenario) != params::to_pairs(running)
    }
}

/// The foot of a lesson's parameter panel: the "Apply & reset" button, enabled
/// when `changed` (the pending parameters differ, or the lesson has its own
/// reason to start over), with `apply_hover` on it, then the share link, whose
/// `query(embed)` is the lesson's own (`Lesson::share_query`) and whose
/// `share_hover` says what the link opens. True when the button was pressed.
pub fn apply_and_share_ui(
    ui: &mut egui::Ui,
    changed: bool,
    apply_hover: &str,
    query: impl Fn(bool) -> String,
    share_hover: &str,
) -> bool {
    let pressed = ui
        .add_enabled(changed, egui::Button::new("Apply & reset"))
        .on_hover_text(apply_hover)
        .clicked();
    ui.separator();
    crate::widgets::share::share_ui(ui, query, share_hover, None);
    pressed
}

/// One row per parameter in `names` (all of the table's when empty, but the
/// preset). Changed values (against `running`) get a dot. Returns true when a
/// value changed.
pub fn params_ui<S: Scenario>(
    ui: &mut egui::Ui,
    pending: &mut PendingParams<S>,
    running: &S,
    names: &[&str],
) -> bool {
    let mut changed = false;
    let rows: Vec<&'static params::Param<S>> = if names.is_empty() {
        S::params().iter().filter(|p| p.name != "preset").collect()
    } else {
        names.iter().filter_map(|n| S::param(n)).collect()
    };
    // One parameter per row: its name, then its control below it, so that a
    // narrow panel (or a drawer) shows both whole.
    ui.scope(|ui| {
        ui.spacing_mut().slider_width = (ui.available_width() - 110.0).clamp(80.0, 220.0);
        for param in rows {
            changed |= param_row_ui(ui, pending, running, param);
            ui.add_space(4.0);
        }
    });
    changed
}

fn param_row_ui<S: Scenario>(
    ui: &mut egui::Ui,
    pending: &mut PendingParams<S>,
    running: &S,
    param: &'static params::Param<S>,
) -> bool {
    let name = param.name;
    let current = params::get(&pending.scenario, name).unwrap_or_default();
    ui.horizontal(|ui| {
        ui.label(name).on_hover_text(param.help);
        if params::get(&pending.scenario, name) != params::get(running, name) {
            ui.label(egui::RichText::new("•").color(palette::ORANGE))
                .on_hover_text("Changed: press \"Apply & reset\" to use it");
        }
    });
    let mut new_value: Option<String> = None;
    ui.vertical(|ui| {
        match param.kind {
            ParamKind::Number { min, max } => {
                let mut v = current.parse::<f64>().unwrap_or(min);
                let logarithmic = min > 0.0 && max / min >= 100.0;
                let response = ui.add(
                    egui::Slider::new(&mut v, min..=max)
                        .logarithmic(logarithmic)
                        .suffix(if param.unit.is_empty() {
                            String::new()
                        } else {
                            format!(" {}", param.unit)
                        }),
                );
                if response.on_hover_text(param.help).changed() {
                    new_value = Some(params::format_number(v));
                }
            }
            ParamKind::Count { min, max } => {
                let mut v = current.parse::<u64>().unwrap_or(min);
                let response = ui.add(egui::DragValue::new(&mut v).range(min..=max));
                if response.on_hover_text(param.help).changed() {
                    new_value = Some(v.to_string());
                }
            }
            ParamKind::Choice(words) => {
                egui::ComboBox::from_id_salt(("param", name))
                    .selected_text(current.clone())
                    .show_ui(ui, |ui| {
                        for word in words {
                            if ui.selectable_label(current == *word, *word).clicked() {
                                new_value = Some((*word).to_owned());
                            }
                        }
                    })
                    .response
                    .on_hover_text(param.help)
                    .widget_info(|| egui::WidgetInfo::labeled(egui::Role::ComboBox, true, name));
            }
        }
        if let Some(issue) = pending.issues.get(name) {
            ui.colored_label(palette::VERMILLION, issue);
        }
    });
    match new_value {
        Some(value) => {
            pending.set(name, &value);
            true
        }
        None => false,
    }
}
