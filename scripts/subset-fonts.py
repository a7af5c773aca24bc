#!/usr/bin/env python3
"""Makes SLAM Lab's two fonts, assets/fonts/UbuntuLight-derivative-SlamLab.ttf and
assets/fonts/Hack-derivative-SlamLab.ttf: egui's default fonts (Ubuntu Light and Hack, from
the epaint_default_fonts crate) cut down to the characters SLAM Lab draws, so that the
browser download carries 0.33 MB of fonts instead of 0.67 MB (docs/web-build.md).

The fonts are committed; the build does not run this script. Run it again after
updating egui (new upstream fonts) or when a lesson's text needs a character outside
the ranges below (the test `fonts::tests::every_character_of_the_sources_is_in_the_fonts`
in crates/slamlab-app/src/fonts.rs fails and names it):

    python3 scripts/subset-fonts.py

Needs fontTools (Debian: python3-fonttools; the committed fonts were made with 4.68).

What is kept, of each font's characters:
- the ranges below, for what students type or load (file names): ASCII, Latin-1 and
  Latin Extended-A, spacing modifier letters and combining marks (decomposed accents),
  Greek, and general punctuation (dashes, quotes, ellipsis);
- every other character that appears in the Rust sources of slamlab-app, slamlab-sim
  and slamlab-core (string literals, `\\u{...}` escapes; comments too, to be safe): the
  arrows, operators and symbols the lessons draw;
- the glyphs those reach through the fonts' substitution tables (ligatures), kerning
  and every layout feature.
Left out: the TrueType hinting instructions, half of each font's bytes (egui hints the
outlines with skrifa's autohinter instead, which it links anyway; text stays sharp),
other arrows, operators and symbols, Cyrillic, Latin Extended-B and Additional, box
drawing, private use.

Licences (assets/fonts/README.md): a subset is a Modified Version that is not
"Substantially Changed" (its glyphs are the original's), which the Ubuntu Font Licence
1.0 (condition 2c) names "the name of the Original Version, with 'derivative X'
appended": "Ubuntu Light derivative SLAM Lab". The subset of Hack (MIT, and the
Bitstream Vera licence, which reserves only the names "Bitstream" and "Vera") is named
the same way, "Hack derivative SLAM Lab". The copyright and licence notices are kept.
"""

import json
import pathlib
import re
import subprocess
import sys

from fontTools import subset
from fontTools.ttLib import TTFont

REPO = pathlib.Path(__file__).resolve().parent.parent
OUT = REPO / "assets" / "fonts"
SOURCES = ["crates/slamlab-app/src", "crates/slamlab-sim/src", "crates/slamlab-core/src"]

RANGES = [
    (0x0020, 0x007E),  # ASCII
    (0x00A0, 0x017F),  # Latin-1 Supplement, Latin Extended-A
    (0x02B0, 0x036F),  # spacing modifier letters, combining diacritical marks
    (0x0370, 0x03FF),  # Greek
    (0x2000, 0x206F),  # general punctuation (dashes, quotes, ellipsis)
]

# (upstream file, new family, new PostScript name and file name, style)
FONTS = [
    ("Ubuntu-Light.ttf", "Ubuntu Light derivative SLAM Lab", "UbuntuLight-derivative-SlamLab", "Regular"),
    ("Hack-Regular.ttf", "Hack derivative SLAM Lab", "Hack-derivative-SlamLab", "Regular"),
]


def upstream_fonts_dir():
    """The fonts directory of the epaint_default_fonts crate in Cargo.lock."""
    meta = json.loads(
        subprocess.run(
            ["cargo", "metadata", "--format-version", "1", "--locked"],
            cwd=REPO,
            check=True,
            capture_output=True,
            text=True,
        ).stdout
    )
    for package in meta["packages"]:
        if package["name"] == "epaint_default_fonts":
            return pathlib.Path(package["manifest_path"]).parent / "fonts", package["version"]
    sys.exit("subset-fonts.py: epaint_default_fonts is not in Cargo.lock")


def source_characters():
    """Every non-ASCII character of SLAM Lab's sources, escapes included."""
    chars = set()
    for root in SOURCES:
        for path in sorted((REPO / root).rglob("*.rs")):
            text = path.read_text(encoding="utf-8")
            chars.update(ord(c) for c in text if ord(c) > 0x7E)
            chars.update(int(h, 16) for h in re.findall(r"\\u\{([0-9a-fA-F]+)\}", text))
    return chars


def rename(font, family, postscript, style, upstream_version):
    """New names (the Ubuntu Font Licence's condition 2c for a modified version)."""
    full = family if style == "Regular" else f"{family} {style}"
    names = {
        1: family,
        2: style,
        3: f"{postscript}; subset of egui {upstream_version}'s font for SLAM Lab",
        4: full,
        6: postscript,
    }
    table = font["name"]
    for record in list(table.names):
        if record.nameID in (16, 17, 18, 21, 22):  # typographic names: not needed
            table.removeNames(nameID=record.nameID)
    for name_id, value in names.items():
        table.setName(value, name_id, 3, 1, 0x409)
        if table.getName(name_id, 1, 0, 0) is not None:
            table.setName(value, name_id, 1, 0, 0)
    if "CFF " in font:
        sys.exit("subset-fonts.py: CFF fonts are not expected here")


def main():
    fonts_dir, version = upstream_fonts_dir()
    wanted = set()
    for lo, hi in RANGES:
        wanted.update(range(lo, hi + 1))
    wanted |= source_characters()
    OUT.mkdir(parents=True, exist_ok=True)
    for upstream, family, postscript, style in FONTS:
        font = TTFont(fonts_dir / upstream)
        has = set(font.getBestCmap())
        options = subset.Options()
        options.layout_features = ["*"]  # kerning, ligatures, marks: as upstream
        options.name_IDs = ["*"]
        options.name_languages = ["*"]
        options.name_legacy = True
        options.notdef_outline = True
        # No TrueType instructions: egui then hints the outlines with skrifa's autohinter
        # (FreeType's), which it links anyway. The instructions were half of each font.
        options.hinting = False
        options.drop_tables += ["hdmx", "VDMX", "DSIG", "TTFA"]  # unused by egui's reader
        subsetter = subset.Subsetter(options)
        subsetter.populate(unicodes=sorted(wanted & has))
        subsetter.subset(font)
        rename(font, family, postscript, style, version)
        out = OUT / f"{postscript}.ttf"
        font.save(out)
        kept = len(font.getBestCmap())
        print(f"{out.relative_to(REPO)}: {kept} of {len(has)} characters, {out.stat().st_size} bytes")


if __name__ == "__main__":
    main()
