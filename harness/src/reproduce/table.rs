//! Figure data as small tables: written as CSV (atomically), read back for golden comparisons.
//!
//! Numbers follow the one CSV convention of the crate ([`crate::report::csv_number`]: shortest
//! round-trip text, exponent form below 1e-4 and from 1e15, a missing value as an empty field),
//! so reading a file gives back exactly the numbers written.

use crate::error::Error;
use crate::report::AtomicFile;
use std::path::Path;

/// A cell: a number or a label.
#[derive(Clone, Debug, PartialEq)]
pub enum Cell {
    /// A number, written by [`crate::report::csv_number`] (a non-finite one as an empty field).
    Num(f64),
    /// Text, written as is (a cell that does not parse as a number reads back as text).
    Text(String),
}

impl Cell {
    /// The number, if the cell holds one.
    pub fn num(&self) -> Option<f64> {
        match self {
            Cell::Num(x) => Some(*x),
            Cell::Text(_) => None,
        }
    }

    fn render(&self) -> String {
        match self {
            Cell::Text(s) => s.clone(),
            Cell::Num(x) => crate::report::csv_number(*x),
        }
    }

    fn parse(s: &str) -> Cell {
        match s.trim().parse::<f64>() {
            Ok(x) => Cell::Num(x),
            Err(_) => Cell::Text(s.to_string()),
        }
    }
}

impl From<f64> for Cell {
    fn from(x: f64) -> Self {
        Cell::Num(x)
    }
}
impl From<usize> for Cell {
    fn from(x: usize) -> Self {
        Cell::Num(x as f64)
    }
}
impl From<u64> for Cell {
    fn from(x: u64) -> Self {
        Cell::Num(x as f64)
    }
}
impl From<i64> for Cell {
    fn from(x: i64) -> Self {
        Cell::Num(x as f64)
    }
}
impl From<&str> for Cell {
    fn from(x: &str) -> Self {
        Cell::Text(x.to_string())
    }
}
impl From<String> for Cell {
    fn from(x: String) -> Self {
        Cell::Text(x)
    }
}

/// A named table (its name is its file name, e.g. `fig1_snapshots.csv`).
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    /// The file name the table is written under.
    pub name: String,
    /// The column headers (the CSV's first line).
    pub columns: Vec<String>,
    /// The rows, each with one cell per column.
    pub rows: Vec<Vec<Cell>>,
}

impl Table {
    /// An empty table named `name` (its file name) with these column headers.
    pub fn new(name: &str, columns: &[&str]) -> Self {
        Table {
            name: name.to_string(),
            columns: columns.iter().map(|c| c.to_string()).collect(),
            rows: Vec::new(),
        }
    }

    /// Append a row (one cell per column; checked in debug builds).
    pub fn push(&mut self, row: Vec<Cell>) {
        debug_assert_eq!(row.len(), self.columns.len(), "{}", self.name);
        self.rows.push(row);
    }

    /// The position of the column headed `name`, if there is one.
    pub fn column(&self, name: &str) -> Option<usize> {
        self.columns.iter().position(|c| c == name)
    }

    /// The table as CSV bytes: the header line, then the rows.
    pub fn to_csv(&self) -> Result<Vec<u8>, Error> {
        let mut w = csv::Writer::from_writer(Vec::new());
        let err = |source: csv::Error| Error::Csv {
            what: self.name.clone(),
            source,
        };
        w.write_record(&self.columns).map_err(err)?;
        for r in &self.rows {
            w.write_record(r.iter().map(Cell::render)).map_err(err)?;
        }
        w.into_inner().map_err(|e| Error::Io {
            path: self.name.clone().into(),
            source: e.into_error(),
        })
    }

    /// Write `dir/<name>` atomically.
    pub fn write(&self, dir: &Path) -> Result<(), Error> {
        AtomicFile::write_all(dir.join(&self.name), &self.to_csv()?)
    }

    /// Read a CSV written by [`Table::write`].
    pub fn read(path: &Path) -> Result<Table, Error> {
        let io = |source: csv::Error| Error::Csv {
            what: path.display().to_string(),
            source,
        };
        let mut r = csv::Reader::from_path(path).map_err(io)?;
        let columns = r.headers().map_err(io)?.iter().map(String::from).collect();
        let mut rows = Vec::new();
        for rec in r.records() {
            rows.push(rec.map_err(io)?.iter().map(Cell::parse).collect());
        }
        Ok(Table {
            name: path
                .file_name()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default(),
            columns,
            rows,
        })
    }

    /// Every `step`-th row, and the last.
    pub fn thinned(&self, step: usize) -> Table {
        let step = step.max(1);
        let n = self.rows.len();
        let rows = self
            .rows
            .iter()
            .enumerate()
            .filter(|(i, _)| i % step == 0 || i + 1 == n)
            .map(|(_, r)| r.clone())
            .collect();
        Table {
            name: self.name.clone(),
            columns: self.columns.clone(),
            rows,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_round_trip_is_exact() {
        let mut t = Table::new("x.csv", &["k", "value", "label"]);
        for (k, x) in [
            0.1,
            1.0 / 3.0,
            5000.0,
            -2.5e-300,
            f64::MIN_POSITIVE,
            12345.678,
        ]
        .into_iter()
        .enumerate()
        {
            t.push(vec![k.into(), x.into(), format!("row {k}").into()]);
        }
        let dir = tempfile::tempdir().unwrap();
        t.write(dir.path()).unwrap();
        let back = Table::read(&dir.path().join("x.csv")).unwrap();
        assert_eq!(back, t);
    }
}
