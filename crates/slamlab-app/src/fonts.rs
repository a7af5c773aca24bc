//! SLAM Lab's fonts: egui's default fonts cut down to the characters SLAM Lab draws.
//!
//! "Ubuntu Light derivative SLAM Lab" and "Hack derivative SLAM Lab" are Ubuntu Light
//! and Hack as egui 0.37 ships them (`epaint_default_fonts`), keeping ASCII, Latin-1 and
//! Latin Extended-A, combining marks, Greek, general punctuation and every other character
//! of SLAM Lab's sources (the lessons' arrows, operators and symbols), with every kerning
//! pair and ligature of the originals. The TrueType hinting instructions are left out:
//! egui hints the outlines with skrifa's autohinter instead. 0.13 MB of the browser
//! download instead of 0.67 MB (docs/web-build.md). `scripts/subset-fonts.py` makes them; `assets/fonts/README.md`
//! has their licences (the Ubuntu Font Licence's naming of a modified font).
//!
//! The families are egui's: proportional text in the sans font, monospace in the mono
//! font, each falling back to the other and then to egui's icons. Proportional text
//! falls back to the mono font for the arrows and operators Ubuntu Light does not
//! have (→, ∈, ⊕, ⌈ ⌉), so they are drawn in the browser too.

use std::sync::Arc;

use egui::{FontData, FontDefinitions, FontFamily, FontTweak};

/// Ubuntu Light, subset (the proportional font).
pub const SANS: &[u8] = include_bytes!("../../../assets/fonts/UbuntuLight-derivative-SlamLab.ttf");

/// Hack, subset (the monospace font).
pub const MONO: &[u8] = include_bytes!("../../../assets/fonts/Hack-derivative-SlamLab.ttf");

const SANS_NAME: &str = "UbuntuLight-derivative-SlamLab";
const MONO_NAME: &str = "Hack-derivative-SlamLab";
const ICONS_NAME: &str = "egui-icons";

/// The font definitions SLAM Lab installs, the same in the browser and on the desktop.
pub fn definitions() -> FontDefinitions {
    let mut fonts = FontDefinitions::empty();
    fonts
        .font_data
        .insert(SANS_NAME.to_owned(), Arc::new(FontData::from_static(SANS)));
    fonts
        .font_data
        .insert(MONO_NAME.to_owned(), Arc::new(FontData::from_static(MONO)));
    // egui's few icons (`egui::special_emojis`), at egui's own scale.
    fonts.font_data.insert(
        ICONS_NAME.to_owned(),
        Arc::new(
            FontData::from_static(epaint_default_fonts::EGUI_ICONS).tweak(FontTweak {
                scale: 0.90,
                ..Default::default()
            }),
        ),
    );
    let family = |names: [&str; 3]| names.iter().map(|n| (*n).to_owned()).collect();
    fonts.families.insert(
        FontFamily::Proportional,
        family([SANS_NAME, MONO_NAME, ICONS_NAME]),
    );
    fonts.families.insert(
        FontFamily::Monospace,
        family([MONO_NAME, SANS_NAME, ICONS_NAME]),
    );
    fonts
}

/// Installs [`definitions`] (from the next frame on).
pub fn install(ctx: &egui::Context) {
    ctx.set_fonts(definitions());
}

#[cfg(test)]
mod tests {
    use super::*;
    use skrifa::{FontRef, MetadataProvider};
    use std::collections::BTreeSet;
    use std::path::Path;

    fn has(font: &[u8], c: char) -> bool {
        FontRef::new(font)
            .map(|f| f.charmap().map(c).is_some())
            .unwrap_or(false)
    }

    /// Every character of the Rust sources of the app, the simulation and the core
    /// (their labels, explanations, notices and error messages; comments too): ASCII,
    /// what they write as `\u{...}`, and the rest.
    fn source_characters() -> BTreeSet<char> {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let mut chars: BTreeSet<char> = (' '..='~').collect();
        let mut dirs: Vec<_> = ["slamlab-app/src", "slamlab-sim/src", "slamlab-core/src"]
            .iter()
            .map(|d| root.join(d))
            .collect();
        let mut files = 0;
        while let Some(dir) = dirs.pop() {
            let Ok(entries) = std::fs::read_dir(&dir) else {
                panic!("cannot read {}", dir.display());
            };
            for entry in entries.flatten() {
                let path = entry.path();
                if path.is_dir() {
                    dirs.push(path);
                } else if path.extension().is_some_and(|e| e == "rs") {
                    let text = std::fs::read_to_string(&path).unwrap_or_default();
                    files += 1;
                    chars.extend(text.chars().filter(|c| !c.is_ascii()));
                    for escape in text.split("\\u{").skip(1) {
                        let hex: String = escape
                            .chars()
                            .take_while(|c| c.is_ascii_hexdigit())
                            .collect();
                        if let Some(c) = u32::from_str_radix(&hex, 16).ok().and_then(char::from_u32)
                        {
                            chars.insert(c);
                        }
                    }
                }
            }
        }
        assert!(files > 100, "found only {files} source files");
        chars
    }

    /// Each character SLAM Lab writes that egui's full fonts draw is in the subset of
    /// the same font: the subsetting lost no glyph that SLAM Lab can show.
    #[test]
    fn every_character_of_the_sources_is_in_the_fonts() {
        let chars = source_characters();
        assert!(chars.contains(&'σ') && chars.contains(&'θ') && chars.contains(&'≤'));
        let mut missing = Vec::new();
        for &c in &chars {
            if has(epaint_default_fonts::UBUNTU_LIGHT, c) && !has(SANS, c) {
                missing.push(format!("{c} U+{:04X} (sans)", c as u32));
            }
            if has(epaint_default_fonts::HACK_REGULAR, c) && !has(MONO, c) {
                missing.push(format!("{c} U+{:04X} (mono)", c as u32));
            }
        }
        assert!(
            missing.is_empty(),
            "not in the subset fonts (run scripts/subset-fonts.py): {missing:?}"
        );
    }

    /// The characters the lessons draw most, and the arrows that only the mono font
    /// has, are drawn in proportional text.
    #[test]
    fn the_lessons_symbols_are_in_the_proportional_family() {
        for c in "σθΣΔπμ≤≥²→←↑↓×·°µ±√∞≈−–—…•₁⊕∈⌈⌉⟨⟩".chars()
        {
            assert!(has(SANS, c) || has(MONO, c), "{c} U+{:04X}", c as u32);
        }
        let fonts = definitions();
        assert_eq!(
            fonts.families[&FontFamily::Proportional],
            vec![SANS_NAME, MONO_NAME, ICONS_NAME]
        );
        assert_eq!(
            fonts.families[&FontFamily::Monospace],
            vec![MONO_NAME, SANS_NAME, ICONS_NAME]
        );
    }

    /// What a student may type or load (a file name in a European language, decomposed
    /// accents, dashes and quotes) is drawn as the original fonts draw it.
    #[test]
    fn typed_text_keeps_its_characters() {
        let ranges = [
            0x20..=0x7E,     // ASCII
            0xA0..=0x17F,    // Latin-1, Latin Extended-A
            0x2B0..=0x36F,   // modifier letters, combining marks
            0x370..=0x3FF,   // Greek
            0x2000..=0x206F, // general punctuation
        ];
        let mut checked = 0;
        for c in ranges.into_iter().flatten().filter_map(char::from_u32) {
            for (font, upstream) in [
                (SANS, epaint_default_fonts::UBUNTU_LIGHT),
                (MONO, epaint_default_fonts::HACK_REGULAR),
            ] {
                if has(upstream, c) {
                    assert!(has(font, c), "{c} U+{:04X}", c as u32);
                    checked += 1;
                }
            }
        }
        assert!(checked > 600, "{checked} characters checked");
    }

    /// The subset fonts are renamed (the Ubuntu Font Licence's condition 2c) and are
    /// smaller than the originals.
    #[test]
    fn the_fonts_are_renamed_subsets() {
        for (font, name, upstream) in [
            (
                SANS,
                "Ubuntu Light derivative SLAM Lab",
                epaint_default_fonts::UBUNTU_LIGHT,
            ),
            (
                MONO,
                "Hack derivative SLAM Lab",
                epaint_default_fonts::HACK_REGULAR,
            ),
        ] {
            let Ok(font_ref) = FontRef::new(font) else {
                panic!("{name} does not parse");
            };
            let family: Vec<String> = font_ref
                .localized_strings(skrifa::string::StringId::FAMILY_NAME)
                .map(|s| s.to_string())
                .collect();
            assert!(
                !family.is_empty() && family.iter().all(|f| f == name),
                "{family:?}"
            );
            assert!(
                font.len() * 10 < upstream.len() * 7,
                "{name}: {} bytes",
                font.len()
            );
        }
    }
}
