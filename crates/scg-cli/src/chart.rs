//! Plot pieces shared by `scg cost` and `scg study`.

use plotters::coord::CoordTranslate;
use plotters::prelude::*;

/// Draw the series legend of `chart`: black border on translucent white.
pub(crate) fn legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
) -> Result<(), String> {
    chart
        .configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE.mix(0.8))
        .draw()
        .map_err(|e| e.to_string())
}
