//! The crate's errors: [`PlotError`], why a chart or picture could not be made, and
//! [`DrawError`], why drawing one failed (in plotters, for lack of data, or in ffmpeg).
//! Uses plotters' error types only to turn them into text.
//!
//! A variant that wraps another error prints it in its own message and holds it as a
//! plain field (`error`), not as its `source()`: each message is said once in the chain
//! ([`skg_core::error_text`]).

use std::path::PathBuf;

use plotters::drawing::DrawingAreaErrorKind;

use skg_sweep::SweepError;

/// Why a chart could not be drawn.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// The data cannot make the chart asked for (missing column, no points, …).
    #[error("{0}")]
    Data(String),
    /// A results file that cannot be read or has a bad cell.
    #[error(transparent)]
    Results(#[from] SweepError),
    /// Drawing a chart or picture failed (in plotters, for lack of data in a panel, or in
    /// ffmpeg).
    #[error("drawing {path}: {error}")]
    Draw {
        /// The chart file.
        path: PathBuf,
        /// What failed.
        error: DrawError,
    },
    /// A solve's `summary.json` is not valid JSON.
    #[error("{path}: {error}")]
    Summary {
        /// The file.
        path: PathBuf,
        /// The JSON parser's error (with its line and column).
        error: serde_json::Error,
    },
    /// The scene of a picture of the motion is invalid.
    #[error(transparent)]
    Scene(#[from] skg_core::scene::SceneError),
    /// A trajectory or reference CSV cannot be read.
    #[error(transparent)]
    Table(#[from] skg_core::check::CheckError),
    /// A chart's temporary file or its directory could not be made.
    #[error(transparent)]
    Output(#[from] skg_core::output::OutputError),
    /// A chart or its directory could not be written.
    #[error("cannot write {path}: {error}")]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// What the system said.
        error: std::io::Error,
    },
}

/// Why drawing failed ([`PlotError::Draw`] names the file).
#[derive(Debug, thiserror::Error)]
pub enum DrawError {
    /// plotters or its backend failed (its message: the error's type depends on the
    /// backend, which a chart's file type chooses).
    #[error("{0}")]
    Plotters(String),
    /// A panel has no data to draw.
    #[error("{0}")]
    NoData(String),
    /// ffmpeg (for an MP4) could not be started.
    #[error("cannot run ffmpeg ({error}): an MP4 needs ffmpeg on PATH (Debian: apt-get install ffmpeg); a .gif needs nothing")]
    FfmpegMissing {
        /// What the system said.
        error: std::io::Error,
    },
    /// A frame could not be passed to ffmpeg, or ffmpeg could not be waited for.
    #[error("{doing} ffmpeg: {error}")]
    FfmpegPipe {
        /// `writing to` or `waiting for`.
        doing: &'static str,
        /// What the system said.
        error: std::io::Error,
    },
    /// ffmpeg ended with an error.
    #[error("ffmpeg failed ({status}): {stderr}")]
    Ffmpeg {
        /// Its exit status.
        status: std::process::ExitStatus,
        /// What it wrote to stderr.
        stderr: String,
    },
}

impl<E: std::error::Error + Send + Sync + 'static> From<DrawingAreaErrorKind<E>> for DrawError {
    fn from(e: DrawingAreaErrorKind<E>) -> DrawError {
        DrawError::Plotters(match &e {
            DrawingAreaErrorKind::BackendError(plotters_backend::DrawingErrorKind::DrawingError(inner)) => backend_error_text(inner),
            _ => e.to_string(),
        })
    }
}

/// The message of a drawing backend's error: what the system said (`No space left on
/// device (os error 28)`), not the Debug text plotters' bitmap backend displays
/// (`GifEncodingError(Io(Os { code: 28, … }))`).
pub(crate) fn backend_error_text(e: &(dyn std::error::Error + 'static)) -> String {
    use plotters_bitmap::BitMapBackendError as B;
    match e.downcast_ref::<B>() {
        Some(B::IOError(io)) => io.to_string(),
        Some(B::GifEncodingError(g)) => g.to_string(),
        Some(B::ImageError(i)) => i.to_string(),
        Some(B::InvalidBuffer) => "the picture's pixel buffer has the wrong size".to_string(),
        None => e.to_string(),
    }
}

impl DrawError {
    pub(crate) fn no_data(message: impl Into<String>) -> DrawError {
        DrawError::NoData(message.into())
    }
}
