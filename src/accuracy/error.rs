//! What goes wrong in an accuracy analysis, as data: a location in an input file with the line
//! and what to do, or a reason the measurements cannot give the figures. Rendered only when
//! displayed (`file:line:col: error: …`, the line, a caret, `= help: …`).

use std::fmt;
use std::path::PathBuf;

/// A place in an input file: the message, the line as written and a caret under the field.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Located {
    /// The input file, as given.
    pub path: PathBuf,
    /// 1-based line.
    pub line: u64,
    /// 1-based column (in characters of the line) of the first character the caret marks.
    pub column: usize,
    /// How many characters the caret covers (at least 1).
    pub width: usize,
    /// The line as written, without its line break.
    pub line_text: String,
    /// What is wrong, without the location (the `error:` line's text).
    pub message: String,
    /// What to do; empty when there is nothing to add.
    pub hint: String,
}

impl fmt::Display for Located {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let gutter = self.line.to_string().len();
        writeln!(
            f,
            "{}:{}:{}: error: {}",
            self.path.display(),
            self.line,
            self.column,
            self.message
        )?;
        writeln!(f, "{:gutter$} |", "")?;
        writeln!(f, "{} | {}", self.line, self.line_text)?;
        let pad: String = self
            .line_text
            .chars()
            .take(self.column.saturating_sub(1))
            .map(|c| if c == '\t' { '\t' } else { ' ' })
            .collect();
        write!(f, "{:gutter$} | {pad}{}", "", "^".repeat(self.width.max(1)))?;
        if !self.hint.is_empty() {
            write!(f, "\n{:gutter$} = help: {}", "", self.hint)?;
        }
        Ok(())
    }
}

/// The error of the accuracy analysis.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum AccuracyError {
    /// A file could not be read.
    #[error("{}: {error}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// Why it could not be read.
        #[source]
        error: std::io::Error,
    },
    /// Bad input at a place in a file.
    #[error("{0}")]
    Input(Box<Located>),
    /// A file with neither a header nor data.
    #[error("{}: the file is empty (start it with its column names)", path.display())]
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// No commanded pose.
    #[error("no commanded poses: the commanded file needs one row per pose")]
    NoCommandedPoses,
    /// A commanded pose visited fewer than twice.
    #[error(
        "point `{point}` has {visits} visit(s); repeatability needs at least 2 (ISO 9283 asks for 30 cycles)"
    )]
    TooFewVisits {
        /// The commanded point's name.
        point: String,
        /// How many visits the measurement has of it.
        visits: usize,
    },
    /// A point of the later measurement that the earlier one lacks.
    #[error(
        "point `{point}` is not in the earlier measurement; compare measurements of the same poses"
    )]
    NotInEarlier {
        /// The point's name.
        point: String,
    },
    /// A commanded path of fewer than two points.
    #[error(
        "the commanded path has {points} point(s); it needs at least 2 (start and end of a line)"
    )]
    PathTooShort {
        /// How many points the commanded path has.
        points: usize,
    },
    /// Two consecutive commanded path points at the same place (1-based).
    #[error("commanded path points {first} and {} coincide; remove the repeated point", first + 1)]
    CoincidentPoints {
        /// The first of the two, 1-based.
        first: usize,
    },
    /// Zero planes asked for.
    #[error("the number of planes must be at least 1")]
    NoPlanes,
    /// Fewer than two usable runs.
    #[error(
        "{used} run(s) along the path in the commanded direction; path repeatability needs at least 2 (found {found} run(s) in all)"
    )]
    TooFewRuns {
        /// Runs in the commanded direction (the ones the figures use).
        used: usize,
        /// Runs found in either direction.
        found: usize,
    },
    /// A run that does not reach a plane.
    #[error(
        "run `{run}` does not cross the plane at s = {s:.3} mm; record each run over the whole path"
    )]
    NoCrossing {
        /// The run's name (its cycle, or its number when found from the motion).
        run: String,
        /// The plane's arc length along the commanded path, mm.
        s: f64,
    },
    /// Runs to be found from the motion, but the recording has no times.
    #[error(
        "without a cycle column the runs are found from the motion, which needs a time column `t`"
    )]
    NoTimes,
    /// Too few samples to find runs in.
    #[error("{samples} samples are too few to find runs in (at least {needed})")]
    TooFewSamples {
        /// Samples in the recording.
        samples: usize,
        /// The least number the run finder works with.
        needed: usize,
    },
    /// A recording that does not move.
    #[error("the recording does not move; nothing to cut into runs")]
    Standing,
    /// plotters refused to draw.
    #[error("cannot draw the plot: {0}")]
    Plot(String),
}

impl AccuracyError {
    pub(crate) fn plot(e: impl fmt::Display) -> AccuracyError {
        AccuracyError::Plot(e.to_string())
    }

    /// The location, for an input error.
    pub fn location(&self) -> Option<&Located> {
        match self {
            AccuracyError::Input(l) => Some(l),
            _ => None,
        }
    }
}
