//! "Share this setup": the link that reopens the running setup, for instructors to
//! share or embed: the lesson's own pairs (seed, parameters not at their default)
//! followed by the shell's figure keys (`tick=`, `legend=`, `zoom=`, …, so the figure
//! opens where the student is). Every lesson's parameter panel ends with it.

/// The shell's figure keys for this frame, as query suffixes (`&tick=42&legend=1`):
/// for the full app and for an embed.
#[derive(Clone, Debug, Default)]
struct FigureSuffix {
    full: String,
    embed: String,
}

fn suffix_id() -> egui::Id {
    egui::Id::unique("slamlab_share_figure_suffix")
}

/// The shell stores the figure keys of this frame (before the lesson's panels draw).
pub fn set_figure_suffix(ctx: &egui::Context, full: String, embed: String) {
    ctx.data_mut(|d| d.insert_temp(suffix_id(), FigureSuffix { full, embed }));
}

/// The share link: a copy button, an embed switch and the query string. `query(embed)`
/// is the lesson's own (`Lesson::share_query`); `hover` says what the link opens;
/// `note` is shown under it (say, that unapplied changes are not in it yet).
pub fn share_ui(
    ui: &mut egui::Ui,
    query: impl Fn(bool) -> String,
    hover: &str,
    note: Option<&str>,
) {
    let id = egui::Id::unique("slamlab_share_embed");
    let mut embed: bool = ui.data(|d| d.get_temp(id)).unwrap_or(false);
    let suffix: FigureSuffix = ui.data(|d| d.get_temp(suffix_id())).unwrap_or_default();
    ui.label(egui::RichText::new("Share this setup").strong())
        .on_hover_text(hover);
    let link = format!(
        "?{}{}",
        query(embed),
        if embed { &suffix.embed } else { &suffix.full }
    );
    ui.horizontal(|ui| {
        if ui
            .button("Copy link")
            .on_hover_text("Copy the query string (add it to the page's address)")
            .clicked()
        {
            ui.ctx().copy_text(link.clone());
        }
        ui.checkbox(&mut embed, "for embedding (embed=1)");
    });
    let mut shown: &str = &link;
    let mut layouter = |ui: &egui::Ui, text: &dyn egui::TextBuffer, wrap_width: f32| {
        let mut job = egui::text::LayoutJob::simple(
            link_for_wrapping(text.as_str()),
            egui::TextStyle::Monospace.resolve(ui.style()),
            ui.visuals().widgets.inactive.text_color(),
            wrap_width,
        );
        job.keep_trailing_whitespace = true;
        ui.fonts_mut(|f| f.layout_job(job))
    };
    ui.add(
        egui::TextEdit::multiline(&mut shown)
            .desired_rows(2)
            .desired_width(f32::INFINITY)
            .code_editor()
            .interactive(true)
            .layouter(&mut layouter)
            .hint_text("share link"),
    )
    .on_hover_text(hover);
    if let Some(note) = note {
        ui.label(note);
    }
    ui.data_mut(|d| d.insert_temp(id, embed));
}

/// The link as it is drawn: its hyphens as non-breaking hyphens (U+2011, the same
/// glyph), so that a narrow panel wraps the link at its punctuation (after an `&`,
/// a `,` or an `=`) and never inside a lesson's name ("landmark-" / "slam"). One
/// character for one, so the text field's cursor and copy (of the link itself)
/// are unchanged.
pub fn link_for_wrapping(link: &str) -> String {
    link.replace('-', "\u{2011}")
}

#[cfg(test)]
mod wrapping_tests {
    use super::*;

    #[test]
    fn a_link_keeps_its_characters_and_its_lesson_names_whole() {
        let link = "?lesson=landmark-slam&estimator=ekf,ukf";
        let shown = link_for_wrapping(link);
        assert_eq!(shown.chars().count(), link.chars().count());
        assert!(!shown.contains('-'));
        assert!(shown.starts_with("?lesson=landmark\u{2011}slam&"));
    }
}
