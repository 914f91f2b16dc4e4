//! Writing charts: the embedded font (registered once), the chart size, the palette, the
//! legend's box, and the writing of a drawing to its files ([`render!`] for a chart's SVG
//! and PNG, [`finish`] for one file), each through a temporary file beside it
//! ([`skg_core::output::temporary_beside`]) that is renamed when complete. Uses plotters
//! and `crate::error`.

use std::path::{Path, PathBuf};
use std::sync::Once;

use plotters::prelude::*;

use crate::{DrawError, PlotError};

static FONT: &[u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

pub(crate) fn register_fonts() {
    REGISTER.call_once(|| {
        // The embedded font is valid; a failure would only mean text is not drawn.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// Size of every chart in pixels (PNG) and user units (SVG).
pub const SIZE: (u32, u32) = (800, 500);

const COLORS: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

pub(crate) fn color(i: usize) -> RGBColor {
    COLORS[i % COLORS.len()]
}

/// Draw a chart with both backends: `stem.svg` and `stem.png` (written to temporary
/// files in the same directory, [`skg_core::output::temporary_beside`], then renamed).
macro_rules! render {
    ($stem:expr, $size:expr, $draw:ident ( $($arg:expr),* )) => {{
        $crate::render::register_fonts();
        let stem: &std::path::Path = $stem;
        let mut written = Vec::new();
        for ext in ["svg", "png"] {
            let path = stem.with_extension(ext);
            let tmp = skg_core::output::temporary_beside(&path)?;
            let drawn: Result<(), $crate::DrawError> = if ext == "svg" {
                let root = plotters::prelude::SVGBackend::new(&tmp, $size).into_drawing_area();
                $draw(&root, $($arg),*).and_then(|_| Ok(root.present()?))
            } else {
                let root = plotters::prelude::BitMapBackend::new(&tmp, $size).into_drawing_area();
                $draw(&root, $($arg),*).and_then(|_| Ok(root.present()?))
            };
            written.push($crate::render::finish(&tmp, &path, drawn)?);
        }
        Ok(written)
    }};
}

pub(crate) use render;

/// Draw a chart's legend: the series' labels in a framed, nearly opaque white box at
/// `position`, in `size`-pixel type.
pub(crate) fn draw_legend<'a, DB: DrawingBackend<ErrorType: 'static> + 'a, CT: plotters::coord::CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
    size: u32,
) -> Result<(), DrawError> {
    Ok(chart
        .configure_series_labels()
        .position(position)
        .label_font(("sans-serif", size))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?)
}

/// Rename the finished temporary file over `path`, or remove it when drawing failed.
pub(crate) fn finish(tmp: &Path, path: &Path, drawn: Result<(), DrawError>) -> Result<PathBuf, PlotError> {
    if let Err(error) = drawn {
        let _ = std::fs::remove_file(tmp);
        return Err(PlotError::Draw { path: path.to_path_buf(), error });
    }
    std::fs::rename(tmp, path).map_err(|error| PlotError::Io { path: path.to_path_buf(), error })?;
    Ok(path.to_path_buf())
}
