//! What the units' SVG figures share: the velocity-against-grain chart of Fig. 1 and 3. Every figure is a [`LineChart`] in the one plotting style
//! (`report::style`).

use crate::error::Error;
use crate::report::plot::{LineChart, Series};

/// Velocity against grain number, one line per snapshot, with dashed vertical lines at `marks`
/// (interfaces, container edges; one legend entry per distinct label).
pub(crate) fn velocity_plot(
    caption: &str,
    first_grain: i64,
    series: &[(String, &[f64])],
    marks: &[(f64, &str)],
) -> Result<String, Error> {
    LineChart {
        title: caption,
        x_label: "grain number",
        y_label: "velocity (program units)",
        series: series
            .iter()
            .map(|(label, v)| Series {
                name: label.clone(),
                points: v
                    .iter()
                    .enumerate()
                    .map(|(i, &y)| (first_grain as f64 + i as f64, y))
                    .collect(),
                ..Default::default()
            })
            .collect(),
        edges: marks.iter().map(|&(x, l)| (x, l.to_string())).collect(),
        ..Default::default()
    }
    .to_svg()
}
