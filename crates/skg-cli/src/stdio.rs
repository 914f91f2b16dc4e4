//! The process's standard output and standard error, written without panicking.
//!
//! `println!` and `eprintln!` panic when their stream cannot be written ("failed
//! printing to stdout", exit status 101): a reader that closed its end of a pipe
//! (`skg-solve status DIR | head -1`), a full device (`> /dev/full`). Every line the
//! commands print goes through [`out!`] (stdout: the command's report and tables) or
//! [`note!`] (stderr: progress, notes, warnings and errors) instead, and `main` prints
//! clap's help and messages through [`clap_message`].
//!
//! A failed write is remembered, not returned: the command goes on, because its files
//! and its verdict do not depend on whether anyone reads its report (a solve whose
//! progress lines nobody reads still writes its trajectory, a `check` that exceeds a
//! tolerance still exits 4), and later lines to that stream are dropped. [`finish`], at
//! the end of `main`, turns the remembered failures into the exit status:
//!
//! - a closed pipe (EPIPE) on either stream ends quietly with the command's own status,
//!   0 when it succeeded: the reader took what it wanted, as with ripgrep and cargo;
//! - any other write error (a full device, an I/O error) is an I/O error, status 1
//!   unless the command already failed, with `error: writing to stdout: …` on stderr
//!   while stderr can still be written.
//!
//! Progress bars (indicatif) draw only when stderr is a terminal and ignore their own
//! write errors; they do not come through here.
//!
//! Uses the standard library and clap's error type; `main` and the commands use this
//! module, not the other way round.

use std::fmt;
use std::io::{self, Write};
use std::process::ExitCode;
use std::sync::{Mutex, PoisonError};

/// One of the two streams the commands write to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stream {
    /// Standard output: the command's report, tables, `--help`.
    Stdout,
    /// Standard error: progress, notes, warnings, errors.
    Stderr,
}

impl fmt::Display for Stream {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Stream::Stdout => "stdout",
            Stream::Stderr => "stderr",
        })
    }
}

/// The first failed write to a stream: `writing to stdout: No space left on device (os
/// error 28)`.
#[derive(Debug, thiserror::Error)]
#[error("writing to {stream}: {error}")]
pub struct StreamError {
    /// The stream.
    pub stream: Stream,
    /// What the write returned (printed in this message, so not a `source`).
    pub error: io::Error,
}

impl StreamError {
    /// A closed pipe: the reader went away, which is not an error of this process.
    fn is_closed_pipe(&self) -> bool {
        self.error.kind() == io::ErrorKind::BrokenPipe
    }
}

/// The first failure of each stream (stdout, stderr); a stream that failed is not
/// written again.
static FAILED: Mutex<[Option<StreamError>; 2]> = Mutex::new([None, None]);

fn index(stream: Stream) -> usize {
    match stream {
        Stream::Stdout => 0,
        Stream::Stderr => 1,
    }
}

/// Write one line to `stream`, unless it already failed; remember a failure. Used by
/// [`out!`] and [`note!`].
pub fn line(stream: Stream, text: fmt::Arguments<'_>) {
    write_with(stream, |w| writeln!(w, "{text}"));
}

/// clap's help, version or usage message (on stdout or stderr as clap chooses) and its
/// exit status (0 for `--help` and `--version`, 2 for a usage error).
pub fn clap_message(e: &clap::Error) -> ExitCode {
    let stream = if e.use_stderr() { Stream::Stderr } else { Stream::Stdout };
    let mut failed = FAILED.lock().unwrap_or_else(PoisonError::into_inner);
    if let Err(error) = e.print() {
        failed[index(stream)].get_or_insert(StreamError { stream, error });
    }
    ExitCode::from(u8::try_from(e.exit_code()).unwrap_or(2))
}

/// Run `write` on the locked stream unless the stream already failed, and remember the
/// error it returns. stdout is line-buffered, so a line reaches the stream (or fails)
/// here.
fn write_with(stream: Stream, write: impl FnOnce(&mut dyn Write) -> io::Result<()>) {
    let mut failed = FAILED.lock().unwrap_or_else(PoisonError::into_inner);
    let slot = &mut failed[index(stream)];
    if slot.is_some() {
        return;
    }
    let result = match stream {
        Stream::Stdout => write(&mut io::stdout().lock()),
        Stream::Stderr => write(&mut io::stderr().lock()),
    };
    if let Err(error) = result {
        *slot = Some(StreamError { stream, error });
    }
}

/// The exit status of the process: the command's `status`, or 1 after a write error
/// other than a closed pipe when the command succeeded (said on stderr while it can be
/// written). Flushes stdout first.
pub fn finish(status: ExitCode) -> ExitCode {
    write_with(Stream::Stdout, |w| w.flush());
    let failed = std::mem::take(&mut *FAILED.lock().unwrap_or_else(PoisonError::into_inner));
    let stderr_writable = failed[index(Stream::Stderr)].is_none();
    let mut status = status;
    for e in failed.iter().flatten().filter(|e| !e.is_closed_pipe()) {
        if stderr_writable {
            let _ = writeln!(io::stderr().lock(), "error: {e}");
        }
        if status == ExitCode::SUCCESS {
            status = ExitCode::FAILURE;
        }
    }
    status
}

/// Print a line on stdout, as `println!` does, without panicking ([`crate::stdio`]).
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::stdio::line($crate::stdio::Stream::Stdout, format_args!($($arg)*))
    };
}

/// Print a line on stderr, as `eprintln!` does, without panicking ([`crate::stdio`]).
macro_rules! note {
    ($($arg:tt)*) => {
        $crate::stdio::line($crate::stdio::Stream::Stderr, format_args!($($arg)*))
    };
}

pub(crate) use {note, out};
