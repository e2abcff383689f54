//! The review of a golden change. When `golden_figures` finds any difference from the golden
//! data (within its tolerances or not) it writes `golden/REVIEW.md`: per file and column, the
//! largest absolute and relative change from the golden file and where (row and key), the
//! tolerance each comparison of the test applies and whether it holds; and
//! `golden/<file>.review.svg` for each file that moved, the golden curves (dashed) under the new
//! ones. CONTRIBUTING.md's review section starts there. Both are left out of git
//! (`.gitignore`), and removed by a run that finds no difference.

use grainchain::report::plot::{LineChart, Series};
use grainchain::report::style::Scale;
use grainchain::reproduce::{Cell, Table};
use std::fmt::Write as _;
use std::path::Path;

/// The largest change of a column and where.
#[derive(Clone, Debug)]
struct Worst {
    row: usize,
    key: String,
    new: f64,
    golden: f64,
    change: f64,
}

/// One column of one file.
#[derive(Debug)]
struct Column {
    file: String,
    column: String,
    key: String,
    rows: usize,
    abs: Option<Worst>,
    rel: Option<Worst>,
    /// The test's comparisons of this column: what it allows, and whether it held.
    checks: Vec<(String, bool)>,
}

/// How a moved file is drawn: its x column (`None`: the row number) and whether both axes are
/// logarithmic.
pub struct Plot<'a> {
    pub file: &'a str,
    pub x: Option<&'a str>,
    pub log: bool,
}

/// Every column measured so far, in the order of the test.
#[derive(Default)]
pub struct Review {
    columns: Vec<Column>,
    tables: Vec<(Table, Table)>,
}

fn cell_text(t: &Table, row: usize, key: &str) -> String {
    t.column(key)
        .and_then(|k| t.rows.get(row).map(|r| r[k].clone()))
        .map(|c| match c {
            Cell::Num(x) => x.to_string(),
            Cell::Text(t) => t,
        })
        .unwrap_or_else(|| (row + 1).to_string())
}

impl Review {
    /// Measure every numeric column that `new` and `golden` share over the rows both have (the
    /// change in the key column, the rows' name, is measured too: a moved key is a change).
    pub fn file(&mut self, name: &str, new: &Table, golden: &Table, key: &str) {
        for (c, column) in new.columns.iter().enumerate() {
            let Some(g) = golden.column(column) else {
                continue;
            };
            let n = new.rows.len().min(golden.rows.len());
            let (mut abs, mut rel): (Option<Worst>, Option<Worst>) = (None, None);
            let mut numeric = false;
            for i in 0..n {
                let (Some(a), Some(b)) = (new.rows[i][c].num(), golden.rows[i][g].num()) else {
                    continue;
                };
                numeric = true;
                let worst = |change: f64| Worst {
                    row: i + 1,
                    key: cell_text(new, i, key),
                    new: a,
                    golden: b,
                    change,
                };
                let d = (a - b).abs();
                // A NaN change (one side not finite) is the largest there is.
                if abs.as_ref().is_none_or(|w| d > w.change || d.is_nan()) && !(d == 0.0) {
                    abs = Some(worst(d));
                }
                let r = d / b.abs();
                if b != 0.0
                    && rel.as_ref().is_none_or(|w| r > w.change || r.is_nan())
                    && !(r == 0.0)
                {
                    rel = Some(worst(r));
                }
            }
            if numeric {
                self.columns.push(Column {
                    file: name.to_string(),
                    column: column.clone(),
                    key: key.to_string(),
                    rows: n,
                    abs,
                    rel,
                    checks: Vec::new(),
                });
            }
        }
        self.tables.push((new.clone(), golden.clone()));
    }

    /// One comparison the test made of `column` of `file`: what it allows, and whether it held.
    pub fn check(&mut self, file: &str, column: &str, allows: String, held: bool) {
        match self
            .columns
            .iter_mut()
            .find(|c| c.file == file && c.column == column)
        {
            Some(c) => c.checks.push((allows, held)),
            None => self.columns.push(Column {
                file: file.to_string(),
                column: column.to_string(),
                key: String::new(),
                rows: 0,
                abs: None,
                rel: None,
                checks: vec![(allows, held)],
            }),
        }
    }

    /// The review as markdown.
    pub fn markdown(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "# Review of a golden change\n\nWritten by `cargo test --test validation golden_figures::` when the new figure data\n\
             differs from `golden/`. Per file and column: the largest absolute and relative change of\n\
             the new data (`<file>.new`) from the golden file and where, and each comparison the test\n\
             makes with its tolerance and whether it holds. The figures `<file>.review.svg` draw the\n\
             golden curves dashed under the new ones. CONTRIBUTING.md says when to accept.\n"
        );
        let moved: Vec<&Column> = self
            .columns
            .iter()
            .filter(|c| c.abs.is_some() || c.checks.iter().any(|(_, ok)| !ok))
            .collect();
        let _ = writeln!(
            s,
            "{} of {} columns moved or failed a comparison; unmoved columns are not listed.\n",
            moved.len(),
            self.columns.len()
        );
        let _ = writeln!(
            s,
            "| file | column | rows | largest absolute change (row, key: new vs golden) | largest relative change | comparisons (tolerance: holds?) |\n|---|---|---|---|---|---|"
        );
        let show = |w: &Option<Worst>, key: &str| match w {
            None => "0".to_string(),
            Some(w) => format!(
                "{:.3e} (row {}, {key} {}: {} vs {})",
                w.change, w.row, w.key, w.new, w.golden
            ),
        };
        for c in moved {
            let checks = if c.checks.is_empty() {
                "not compared (shown for review)".to_string()
            } else {
                c.checks
                    .iter()
                    .map(|(a, ok)| format!("{a}: **{}**", if *ok { "holds" } else { "FAILS" }))
                    .collect::<Vec<_>>()
                    .join("; ")
            };
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} |",
                c.file,
                c.column,
                c.rows,
                show(&c.abs, &c.key),
                show(&c.rel, &c.key),
                checks
            );
        }
        s
    }

    /// Whether any column moved or any comparison failed.
    pub fn moved(&self) -> bool {
        self.columns
            .iter()
            .any(|c| c.abs.is_some() || c.checks.iter().any(|(_, ok)| !ok))
    }

    /// Write `REVIEW.md` and a `<file>.review.svg` per moved file into `dir`.
    pub fn write(&self, dir: &Path, plots: &[Plot]) {
        std::fs::write(dir.join("REVIEW.md"), self.markdown()).expect("write REVIEW.md");
        for p in plots {
            let moved: Vec<&Column> = self
                .columns
                .iter()
                .filter(|c| c.file == p.file && c.abs.is_some())
                .filter(|c| Some(c.column.as_str()) != p.x && !c.column.starts_with("converged"))
                .collect();
            let Some((new, golden)) = self.tables.iter().find(|(t, _)| t.name == p.file) else {
                continue;
            };
            if moved.is_empty() {
                continue;
            }
            let points = |t: &Table, col: &str| -> Vec<(f64, f64)> {
                let y = t.column(col).unwrap();
                let x = p.x.and_then(|x| t.column(x));
                t.rows
                    .iter()
                    .enumerate()
                    .filter_map(|(i, r)| {
                        let xv = match x {
                            Some(k) => r[k].num()?,
                            None => (i + 1) as f64,
                        };
                        Some((xv, r[y].num()?))
                    })
                    .collect()
            };
            let mut series = Vec::new();
            // At most six columns per figure (the palette's colours stay apart).
            for c in moved.iter().take(6) {
                series.push(Series {
                    name: format!("{} (new)", c.column),
                    points: points(new, &c.column),
                    ..Series::default()
                });
                if golden.column(&c.column).is_some() {
                    series.push(Series {
                        name: format!("{} (golden)", c.column),
                        points: points(golden, &c.column),
                        dashed: true,
                        same_color: true,
                        ..Series::default()
                    });
                }
            }
            let scale = if p.log { Scale::Log } else { Scale::Linear };
            let title = format!("{}: golden (dashed) and new", p.file);
            let chart = LineChart {
                title: &title,
                x_label: p.x.unwrap_or("row"),
                y_label: "value",
                x_scale: scale,
                y_scale: scale,
                series,
                ..LineChart::default()
            };
            let stem = p.file.trim_end_matches(".csv");
            chart
                .write(dir.join(format!("{stem}.review.svg")))
                .expect("write the review figure");
        }
    }

    /// Remove a review left by an earlier failing run (a passing run leaves none).
    pub fn remove_old(dir: &Path, plots: &[Plot]) {
        let _ = std::fs::remove_file(dir.join("REVIEW.md"));
        for p in plots {
            let stem = p.file.trim_end_matches(".csv");
            let _ = std::fs::remove_file(dir.join(format!("{stem}.review.svg")));
        }
    }
}
