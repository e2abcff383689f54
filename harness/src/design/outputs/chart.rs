//! A chart of the design outputs as a value: computed with the other outputs
//! (`DesignReport` in `mod.rs`), drawn when they are written.

use crate::error::Error;
use crate::report::plot::{LineChart, Scale, Series};
use std::path::Path;

/// A chart of the outputs, computed: its title, labels, scales and series (the x axis
/// linear); [`Chart::write`] draws it.
pub(crate) struct Chart {
    pub title: String,
    pub x_label: &'static str,
    pub y_label: &'static str,
    pub y_scale: Scale,
    pub series: Vec<Series>,
}

impl Chart {
    /// Draw it into `path` (SVG).
    pub fn write(&self, path: &Path) -> Result<(), Error> {
        LineChart {
            title: &self.title,
            x_label: self.x_label,
            y_label: self.y_label,
            x_scale: Scale::Linear,
            y_scale: self.y_scale,
            series: self.series.clone(),
            ..Default::default()
        }
        .write(path)?;
        Ok(())
    }
}
