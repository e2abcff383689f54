//! Checks of SVG figures a person reads at a glance, usable on any folder of SVGs (the study's,
//! work-precision's, and later reproduce's): every SVG parses and rasterises to PNG (resvg, pure
//! Rust), and from the SVG's `<text>` elements:
//!
//! - every text lies inside the canvas (its box estimated at 0.6 em per character, the estimate
//!   the style module lays figures out with, `grainchain::report::style::text_width`);
//! - the tick labels of each axis (numeric texts sharing a row below the plot or a right-aligned
//!   column left of it) are unique, both as text and as value;
//! - no tick label has more than 6 significant digits (no `9.999999999999999e-11`);
//! - no integer printed with a zero fraction (`200.0`) unless another label on the same axis
//!   needs the decimal (`0.0 0.5 1.0`);
//! - a log axis (labels evenly spaced in `log10` of their values) spans at most 12 decades.
//!
//! Labels are checked from the SVG text, not from pixels: resvg draws text only with fonts, and
//! the rasterisation uses an empty font database unless `GRAINCHAIN_FIGURES_FONTS` names a font
//! folder (for PNGs a person looks at; set `GRAINCHAIN_FIGURES_PNG` to a folder to keep them).

#![allow(dead_code)]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// One `<text>` element.
#[derive(Clone, Debug)]
pub struct Text {
    pub text: String,
    pub x: f64,
    pub y: f64,
    pub size: f64,
    pub anchor: String,
    pub dy: String,
    pub rotated: bool,
}

fn attr(tag: &str, name: &str) -> Option<String> {
    let key = format!(" {name}=\"");
    let i = tag.find(&key)? + key.len();
    let j = tag[i..].find('"')? + i;
    Some(tag[i..j].to_string())
}

fn unescape(s: &str) -> String {
    s.replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&apos;", "'")
        .replace("&amp;", "&")
}

/// The canvas size and the `<text>` elements of an SVG written by plotters.
pub fn texts(svg: &str) -> ((f64, f64), Vec<Text>) {
    let head = &svg[..svg.find('>').unwrap_or(0)];
    let w = attr(head, "width")
        .and_then(|v| v.parse().ok())
        .unwrap_or(0.0);
    let h = attr(head, "height")
        .and_then(|v| v.parse().ok())
        .unwrap_or(0.0);
    let mut out = Vec::new();
    for chunk in svg.split("<text").skip(1) {
        let Some(end_tag) = chunk.find('>') else {
            continue;
        };
        let tag = &chunk[..end_tag];
        let body = &chunk[end_tag + 1..chunk.find("</text>").unwrap_or(chunk.len())];
        let num = |n: &str| attr(tag, n).and_then(|v| v.parse::<f64>().ok());
        out.push(Text {
            text: unescape(body.trim()),
            x: num("x").unwrap_or(f64::NAN),
            y: num("y").unwrap_or(f64::NAN),
            size: num("font-size").unwrap_or(16.0),
            anchor: attr(tag, "text-anchor").unwrap_or_else(|| "start".into()),
            dy: attr(tag, "dy").unwrap_or_default(),
            rotated: attr(tag, "transform").is_some_and(|t| t.contains("rotate")),
        });
    }
    ((w, h), out)
}

/// The estimated box of a text: (left, top, right, bottom).
pub fn text_box(t: &Text) -> (f64, f64, f64, f64) {
    let len = 0.6 * t.size * t.text.chars().count() as f64;
    let (a0, a1) = match t.anchor.as_str() {
        "middle" => (-len / 2.0, len / 2.0),
        "end" => (-len, 0.0),
        _ => (0.0, len),
    };
    // Vertical extent around y: plotters hangs text by dy ("0.76em": top at y; "0.5ex": centred).
    let (b0, b1) = if t.dy.contains("0.76em") {
        (0.0, t.size)
    } else if t.dy.contains("ex") {
        (-0.5 * t.size, 0.5 * t.size)
    } else {
        (-0.8 * t.size, 0.2 * t.size)
    };
    if t.rotated {
        // rotate(270) about (x, y): the text runs upward, its height to the left and right.
        (t.x + b0, t.y - a1, t.x + b1, t.y - a0)
    } else {
        (t.x + a0, t.y + b0, t.x + a1, t.y + b1)
    }
}

/// Significant digits of a number's text (`0.0001` has 1, `200` 1, `-3.85` 3, `2.5e-7` 2).
pub fn significant_digits(s: &str) -> usize {
    let mantissa = s.split(['e', 'E']).next().unwrap_or("");
    let digits: String = mantissa.chars().filter(|c| c.is_ascii_digit()).collect();
    let trimmed = digits.trim_start_matches('0');
    // Zeros ahead of the first non-zero digit never count; trailing zeros of a whole number
    // ("200") do not either, those after a point ("1.50") do.
    let trimmed = if mantissa.contains('.') {
        trimmed
    } else {
        trimmed.trim_end_matches('0')
    };
    trimmed.len().max(1)
}

fn is_number(s: &str) -> Option<f64> {
    let s = s.trim();
    if s.is_empty() || !s.chars().all(|c| c.is_ascii_digit() || "+-.eE".contains(c)) {
        return None;
    }
    s.parse::<f64>().ok()
}

/// The tick labels of each axis: numeric texts grouped by their row (x axes: same y, centred)
/// or column (y axes: same x, right-aligned). Key: "x@<y>" or "y@<x>".
pub fn axes(texts: &[Text]) -> BTreeMap<String, Vec<(Text, f64)>> {
    let mut out: BTreeMap<String, Vec<(Text, f64)>> = BTreeMap::new();
    for t in texts {
        let Some(v) = is_number(&t.text) else {
            continue;
        };
        if t.rotated {
            continue;
        }
        let key = match t.anchor.as_str() {
            "middle" => format!("x@{}", t.y.round()),
            "end" => format!("y@{}", t.x.round()),
            _ => continue,
        };
        out.entry(key).or_default().push((t.clone(), v));
    }
    out
}

/// The problems of one SVG's text (empty when it reads well).
pub fn check_svg(name: &str, svg: &str) -> Vec<String> {
    let mut bad = Vec::new();
    let ((w, h), texts) = texts(svg);
    if !(w > 0.0 && h > 0.0) {
        bad.push(format!("{name}: no canvas size"));
        return bad;
    }
    for t in &texts {
        let (l, top, r, b) = text_box(t);
        if !(l >= -0.5 && top >= -0.5 && r <= w + 0.5 && b <= h + 0.5) {
            bad.push(format!(
                "{name}: text {:?} at ({}, {}) leaves the {w}x{h} canvas (box {l:.0}..{r:.0} x {top:.0}..{b:.0})",
                t.text, t.x, t.y
            ));
        }
    }
    for (axis, labels) in axes(&texts) {
        let mut seen: Vec<&str> = Vec::new();
        for (t, _) in &labels {
            if seen.contains(&t.text.as_str()) {
                bad.push(format!("{name}: {axis}: label {:?} drawn twice", t.text));
            }
            seen.push(&t.text);
            if significant_digits(&t.text) > 6 {
                bad.push(format!(
                    "{name}: {axis}: label {:?} has more than 6 significant digits",
                    t.text
                ));
            }
        }
        let mut values: Vec<f64> = labels.iter().map(|l| l.1).collect();
        values.sort_by(f64::total_cmp);
        if values.windows(2).any(|w| w[0] == w[1]) {
            bad.push(format!("{name}: {axis}: two labels with the same value"));
        }
        let zero_fraction = |s: &str| {
            let m = s.split(['e', 'E']).next().unwrap_or("");
            m.split_once('.')
                .is_some_and(|(_, f)| !f.is_empty() && f.chars().all(|c| c == '0'))
        };
        let needs_decimals = labels.iter().any(|(t, _)| {
            let m = t.text.split(['e', 'E']).next().unwrap_or("");
            m.split_once('.')
                .is_some_and(|(_, f)| f.chars().any(|c| c != '0'))
        });
        if !needs_decimals {
            for (t, _) in &labels {
                if zero_fraction(&t.text) {
                    bad.push(format!(
                        "{name}: {axis}: integer tick printed as {:?}",
                        t.text
                    ));
                }
            }
        }
        // Log axis: positions linear in log10(value) (and not in value).
        if labels.len() >= 3 && labels.iter().all(|l| l.1 > 0.0) {
            let pos: Vec<(f64, f64)> = labels
                .iter()
                .map(|(t, v)| (if axis.starts_with('x') { t.x } else { t.y }, *v))
                .collect();
            let linear_err = fit_error(&pos, |v| v);
            let log_err = fit_error(&pos, f64::log10);
            if log_err < linear_err {
                let (lo, hi) = (values[0], values[values.len() - 1]);
                if (hi / lo).log10() > 12.0 + 1e-6 {
                    bad.push(format!(
                        "{name}: {axis}: log axis spans {:.1} decades ({lo:e} to {hi:e})",
                        (hi / lo).log10()
                    ));
                }
            }
        }
    }
    bad
}

/// Largest residual (pixels) of a straight-line fit of position against `f(value)`.
fn fit_error(pts: &[(f64, f64)], f: impl Fn(f64) -> f64) -> f64 {
    let xs: Vec<f64> = pts.iter().map(|p| f(p.1)).collect();
    let ys: Vec<f64> = pts.iter().map(|p| p.0).collect();
    let n = xs.len() as f64;
    let (mx, my) = (xs.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n);
    let sxx: f64 = xs.iter().map(|x| (x - mx).powi(2)).sum();
    let sxy: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let b = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    xs.iter()
        .zip(&ys)
        .map(|(x, y)| (y - (my + b * (x - mx))).abs())
        .fold(0.0, f64::max)
}

/// Rasterise an SVG to a PNG image (resvg); the PNG's bytes. Fails on an SVG resvg cannot read
/// or that draws nothing but background.
///
/// Only with the tool's feature `raster` (CI runs the suite with it: `.ci/run`): resvg and its
/// font shaping are some 45 s of a fresh clone's 2-core `cargo test` build for this one check,
/// so a plain `cargo test` checks the figures' text and skips their rasterisation (`None`).
#[cfg(feature = "raster")]
pub fn rasterise(name: &str, svg: &str) -> Result<Option<Vec<u8>>, String> {
    use resvg::{tiny_skia, usvg};
    let mut opt = usvg::Options::default();
    if let Ok(dir) = std::env::var("GRAINCHAIN_FIGURES_FONTS") {
        for f in std::fs::read_dir(dir).into_iter().flatten().flatten() {
            if f.path().extension().is_some_and(|x| x == "ttf") {
                if let Ok(data) = std::fs::read(f.path()) {
                    opt.fontdb_mut().load_font_data(data);
                }
            }
        }
        opt.fontdb_mut().set_sans_serif_family("DejaVu Sans");
    }
    let tree = usvg::Tree::from_str(svg, &opt).map_err(|e| format!("{name}: {e}"))?;
    let size = tree.size().to_int_size();
    let mut pixmap = tiny_skia::Pixmap::new(size.width(), size.height())
        .ok_or_else(|| format!("{name}: empty canvas"))?;
    resvg::render(&tree, tiny_skia::Transform::default(), &mut pixmap.as_mut());
    let inked = pixmap
        .data()
        .chunks(4)
        .filter(|p| p[3] > 0 && (p[0] < 200 || p[1] < 200 || p[2] < 200))
        .count();
    if inked < 1000 {
        return Err(format!(
            "{name}: rasterised to a blank image ({inked} dark pixels)"
        ));
    }
    pixmap
        .encode_png()
        .map(Some)
        .map_err(|e| format!("{name}: {e}"))
}

/// Without the feature `raster`: no rasterisation (see the function above).
#[cfg(not(feature = "raster"))]
pub fn rasterise(_name: &str, _svg: &str) -> Result<Option<Vec<u8>>, String> {
    Ok(None)
}

/// Check every `*.svg` of `dir` (text and rasterisation); each PNG is written into
/// `GRAINCHAIN_FIGURES_PNG` when it is set. Returns the SVGs checked and the problems found.
pub fn check_folder(dir: &Path) -> (Vec<PathBuf>, Vec<String>) {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "svg"))
        .collect();
    files.sort();
    let png_dir = std::env::var_os("GRAINCHAIN_FIGURES_PNG").map(PathBuf::from);
    let mut bad = Vec::new();
    for f in &files {
        let name = f.file_name().unwrap().to_string_lossy().to_string();
        let svg = std::fs::read_to_string(f).unwrap();
        bad.extend(check_svg(&name, &svg));
        match rasterise(&name, &svg) {
            Ok(None) => {}
            Ok(Some(png)) => {
                if let Some(d) = &png_dir {
                    std::fs::create_dir_all(d).unwrap();
                    std::fs::write(d.join(name.replace(".svg", ".png")), png).unwrap();
                }
            }
            Err(e) => bad.push(e),
        }
    }
    (files, bad)
}
