//! The motion as a film ([`animate`]): its [`Format`] by the file's extension, its
//! [`Frames`] and their limits, the frames' times, and the encoding — plotters' GIF
//! encoder, or raw RGB frames piped to ffmpeg for an MP4.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use plotters::prelude::*;

use skg_core::output;

use super::picture::{draw, Shot};
use super::scenery::Scenery;
use super::{data_err, Motion, View};
use crate::render::{finish, register_fonts};
use crate::{DrawError, PlotError};

/// The file formats of [`animate`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// An animated GIF (plotters' GIF backend).
    Gif,
    /// An H.264 MP4 encoded by `ffmpeg` (which must be on PATH).
    Mp4,
    /// A strip of frames side by side ([`strip`](super::strip())).
    Png,
}

impl Format {
    /// The format a file name asks for, by its extension.
    pub fn of(path: &Path) -> Result<Format, PlotError> {
        match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
            Some("gif") => Ok(Format::Gif),
            Some("mp4") => Ok(Format::Mp4),
            Some("png") => Ok(Format::Png),
            _ => Err(data_err(format!("{}: the file name must end in .gif, .mp4 or .png (a strip of frames)", path.display()))),
        }
    }
}

/// Options of an animation.
#[derive(Debug, Clone, Copy)]
pub struct Frames {
    /// Number of frames, evenly spaced in time from the first node to the last.
    pub count: usize,
    /// Frames per second.
    pub fps: f64,
    /// Frame size in pixels.
    pub size: (u32, u32),
}

/// The most frames an animation may have: 400 s of film at 25 frames per second, about
/// four minutes of drawing at the default size (a frame takes about 20 ms).
pub const MAX_FRAMES: usize = 10_000;

/// The most pixels the frames of an animation may have together (frames × width ×
/// height): what is drawn and encoded, and a bound on the file (a GIF stores at most
/// about a byte per pixel; 10 000 frames of the default 640×520 are 3.3·10⁹).
pub const MAX_ANIMATION_PIXELS: u64 = 4_000_000_000;

impl Frames {
    /// Refuse an animation larger than [`MAX_FRAMES`] frames or [`MAX_ANIMATION_PIXELS`]
    /// pixels, or without a positive frame count and rate, before anything is drawn (an
    /// animation of 10⁶ frames runs for hours, its file growing by megabytes a second).
    pub fn check(&self) -> Result<(), PlotError> {
        if self.count == 0 || !(self.fps > 0.0 && self.fps.is_finite()) {
            return Err(data_err("the number of frames and the frame rate must be positive"));
        }
        if self.count > MAX_FRAMES {
            return Err(data_err(format!(
                "{} frames are more than the {MAX_FRAMES} an animation may have: use fewer frames (the film then runs \
                 faster through the motion, or set a lower frame rate)",
                self.count
            )));
        }
        let pixels = self.count as u64 * self.size.0 as u64 * self.size.1 as u64;
        if pixels > MAX_ANIMATION_PIXELS {
            return Err(data_err(format!(
                "{} frames of {}×{} are {pixels} pixels, more than the {MAX_ANIMATION_PIXELS} an animation may have \
                 (they bound its drawing time and its file): use fewer frames or a smaller size",
                self.count, self.size.0, self.size.1
            )));
        }
        Ok(())
    }
}

pub(super) fn frame_times(motion: &Motion, count: usize) -> Vec<f64> {
    let t = motion.solution.times();
    let (t0, t1) = (t[0], t[t.len() - 1]);
    if count == 1 {
        return vec![t1];
    }
    (0..count).map(|i| t0 + (t1 - t0) * i as f64 / (count - 1) as f64).collect()
}

/// The motion as an animation: a GIF, or an MP4 encoded by ffmpeg, of `frames.count`
/// frames with the trail so far, the current position, the walls at the frame's time
/// and a time stamp. `on_frame` is called after each frame (for a progress bar). The
/// file is written to a temporary file beside it, then renamed.
pub fn animate(motion: &Motion, view: &View, frames: &Frames, path: &Path, on_frame: &mut dyn FnMut()) -> Result<PathBuf, PlotError> {
    register_fonts();
    frames.check()?;
    let s = Scenery::new(motion, view.clone())?;
    let times = frame_times(motion, frames.count);
    let tmp = output::temporary_beside(path)?;
    let drawn = match Format::of(path)? {
        Format::Gif => (|| {
            let delay = (1000.0 / frames.fps).round().max(10.0) as u32;
            let root = BitMapBackend::gif(&tmp, frames.size, delay)
                .map_err(|e| DrawError::Plotters(crate::error::backend_error_text(&e)))?
                .into_drawing_area();
            for &t in &times {
                draw(&root, &s, Shot::Frame { t, compact: false })?;
                root.present()?;
                on_frame();
            }
            Ok(())
        })(),
        Format::Mp4 => mp4(&s, &times, frames, &tmp, on_frame),
        Format::Png => return Err(data_err("a .png is a strip of frames: use `strip`")),
    };
    finish(&tmp, path, drawn)
}

fn mp4(s: &Scenery<'_>, times: &[f64], frames: &Frames, tmp: &Path, on_frame: &mut dyn FnMut()) -> Result<(), DrawError> {
    let (w, h) = (frames.size.0 & !1, frames.size.1 & !1); // yuv420p wants even sizes
    let mut child = Command::new("ffmpeg")
        .args([
            "-y",
            "-loglevel",
            "error",
            "-f",
            "rawvideo",
            "-pix_fmt",
            "rgb24",
            "-s",
            &format!("{w}x{h}"),
            "-r",
            &format!("{}", frames.fps),
        ])
        .args(["-i", "-", "-an", "-c:v", "libx264", "-pix_fmt", "yuv420p", "-f", "mp4"])
        .arg(tmp)
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|error| DrawError::FfmpegMissing { error })?;
    let mut stdin = child.stdin.take().expect("piped");
    let mut buf = vec![0u8; (w * h * 3) as usize];
    let mut result = Ok(());
    for &t in times {
        {
            let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
            if let Err(e) = draw(&root, s, Shot::Frame { t, compact: false }).and_then(|_| Ok(root.present()?)) {
                result = Err(e);
                break;
            }
        }
        if let Err(error) = stdin.write_all(&buf) {
            result = Err(DrawError::FfmpegPipe { doing: "writing to", error });
            break;
        }
        on_frame();
    }
    drop(stdin);
    let out = child.wait_with_output().map_err(|error| DrawError::FfmpegPipe { doing: "waiting for", error })?;
    result?;
    if !out.status.success() {
        return Err(DrawError::Ffmpeg { status: out.status, stderr: String::from_utf8_lossy(&out.stderr).trim().to_string() });
    }
    Ok(())
}
