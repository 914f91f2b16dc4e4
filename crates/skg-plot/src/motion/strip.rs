//! Frames of the motion side by side in one PNG ([`strip`]), and the limits of a strip.

use std::path::{Path, PathBuf};

use plotters::prelude::*;

use skg_core::output;

use super::animation::frame_times;
use super::picture::{draw, Shot};
use super::scenery::Scenery;
use super::{data_err, Motion, View};
use crate::render::{finish, register_fonts};
use crate::PlotError;

/// The most frames a strip may have.
pub const MAX_STRIP_FRAMES: usize = 100;

/// The most pixels a strip's picture may have (held in memory at 3 bytes each while it
/// is drawn: 300 MB).
pub const MAX_STRIP_PIXELS: u64 = 100_000_000;

/// Refuse a strip of more than [`MAX_STRIP_FRAMES`] frames or [`MAX_STRIP_PIXELS`]
/// pixels, or of none, before anything is drawn.
pub fn check_strip(count: usize, panel: (u32, u32)) -> Result<(), PlotError> {
    if count == 0 {
        return Err(data_err("a strip needs at least one frame"));
    }
    if count > MAX_STRIP_FRAMES {
        return Err(data_err(format!("a strip of {count} frames is more than the {MAX_STRIP_FRAMES} a strip may have")));
    }
    let pixels = count as u64 * panel.0 as u64 * panel.1 as u64;
    if pixels > MAX_STRIP_PIXELS {
        return Err(data_err(format!(
            "a strip of {count} frames of {}×{} is {pixels} pixels, more than the {MAX_STRIP_PIXELS} a strip may have \
             (the picture is held in memory while it is drawn): use fewer frames or a smaller size",
            panel.0, panel.1
        )));
    }
    Ok(())
}

/// `count` frames of the motion side by side in one PNG, each `panel` pixels, evenly
/// spaced in time (the first at the start, the last at the end).
pub fn strip(motion: &Motion, view: &View, count: usize, panel: (u32, u32), path: &Path) -> Result<PathBuf, PlotError> {
    register_fonts();
    check_strip(count, panel)?;
    let s = Scenery::new(motion, View { title: String::new(), ..view.clone() })?;
    let times = frame_times(motion, count);
    let tmp = output::temporary_beside(path)?;
    let drawn = (|| {
        let root = BitMapBackend::new(&tmp, (panel.0 * count as u32, panel.1)).into_drawing_area();
        root.fill(&WHITE)?;
        for (area, &t) in root.split_evenly((1, count)).iter().zip(&times) {
            draw(area, &s, Shot::Frame { t, compact: true })?;
        }
        Ok(root.present()?)
    })();
    finish(&tmp, path, drawn)
}
