//! Errors of the track model, by cause. Each carries its data; `Display` renders it (a located
//! input error as `file:line:col: error: …` with the line, a caret and what to do, through
//! [`Diagnostic::render`]).

use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::spline::SplineError;
use crate::geometry::rigid_fit::RigidFitError;
use crate::located::Located;
use crate::syntax::{Diagnostic, Span};

/// An error at a place in an input file (a CSV table, a profile): a [`Located`] diagnostic
/// (the span's line only, so a file with many errors holds no copies of itself), with the
/// CSV column it is in.
#[derive(Clone, Debug)]
pub struct LocatedError {
    located: Located,
    /// The CSV column the error is in, if any.
    column_name: Option<String>,
    /// False for a file that is not what it was given as (`/etc/passwd` as a profile): its
    /// text is not echoed.
    quote: bool,
}

impl LocatedError {
    /// An error at `span` of `source` with what to do (`hint`, may be empty).
    pub fn new(
        path: &Path,
        source: Arc<[u8]>,
        span: Span,
        message: impl Into<String>,
        hint: &str,
    ) -> LocatedError {
        let mut diagnostic = Diagnostic::error(span, message);
        if !hint.is_empty() {
            diagnostic = diagnostic.with_hint(hint);
        }
        LocatedError {
            located: Located::in_line(path, &source, diagnostic),
            column_name: None,
            quote: true,
        }
    }

    /// The same error without the file's text: for a file that is not what it claims to be.
    pub fn without_quote(mut self) -> LocatedError {
        self.quote = false;
        self
    }

    /// The same error about a UTF-8 file (a TOML profile): its excerpt decodes so, not as
    /// Latin-1.
    pub fn in_utf8(mut self) -> LocatedError {
        self.located = self.located.in_encoding(crate::syntax::Encoding::Utf8);
        self
    }

    /// The same error, in the CSV column `name`.
    pub fn in_column(mut self, name: &str) -> LocatedError {
        self.column_name = Some(name.to_owned());
        self
    }

    /// The file the error is in.
    pub fn path(&self) -> &Path {
        &self.located.path
    }

    /// 1-based line and column (in bytes) of the error.
    pub fn line_col(&self) -> (usize, usize) {
        self.located.line_col()
    }

    /// What is wrong.
    pub fn message(&self) -> &str {
        &self.located.diagnostic.message
    }

    /// What to do, when there is something to say.
    pub fn hint(&self) -> Option<&str> {
        self.located.diagnostic.hint.as_deref()
    }

    /// The CSV column the error is in.
    pub fn column_name(&self) -> Option<&str> {
        self.column_name.as_deref()
    }

    /// The located diagnostic behind the error.
    pub fn diagnostic(&self) -> &Diagnostic {
        &self.located.diagnostic
    }
}

impl fmt::Display for LocatedError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.quote {
            return self.located.fmt(f);
        }
        let (line, col) = self.line_col();
        let path = self.path().display();
        write!(f, "{path}:{line}:{col}: error: {}", self.message())?;
        if let Some(hint) = self.hint() {
            write!(f, "\n  = help: {hint}")?;
        }
        Ok(())
    }
}

impl std::error::Error for LocatedError {}

/// Why the points measured at one skid position give no trustworthy base frame.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SkidProblem {
    /// Fewer than three points.
    #[error("{count} point(s) measured, a base frame needs at least 3 non-collinear points")]
    TooFewPoints {
        /// Points measured at the skid position.
        count: usize,
    },
    /// The rigid fit has no unique answer.
    #[error("{0}")]
    Degenerate(RigidFitError),
    /// The points lie too close to a line: the rotation about it is barely determined.
    #[error(
        "the points are nearly collinear: the fit's condition number is {condition:.0} (limit {limit:.0}), so noise turns into a large rotation about their line"
    )]
    IllConditioned {
        /// The fit's condition number.
        condition: f64,
        /// The largest accepted.
        limit: f64,
    },
    /// The tracker points are spread `ratio` times as wide as the robot points.
    #[error(
        "the tracker points are spread {ratio:.6e} times as wide as the robot points (a rigid fit needs 1 within {tolerance}): the two point sets are in different units or do not belong together"
    )]
    Scale {
        /// Spread of the tracker points over spread of the robot points.
        ratio: f64,
        /// How far from 1 `ratio` may be.
        tolerance: f64,
    },
    /// The fit's normal matrix is singular: some motion of the frame moves no point.
    #[error("the points do not fix all six degrees of freedom of the frame")]
    Unconstrained,
}

/// Why sampling frames give no straight nominal track.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum NominalProblem {
    /// Fewer than two sampling frames.
    #[error("{count} sampling frame(s), a track model needs at least 2")]
    TooFewFrames {
        /// Sampling frames given.
        count: usize,
    },
    /// The frame origins do not move with the skid (no regression slope).
    #[error("the sampling frames do not move with the skid: no track direction")]
    NoDirection,
    /// The sum of the frame rotations has no nearest rotation (SVD degenerate).
    #[error("the mean of the frame rotations is degenerate")]
    DegenerateRotation,
    /// The base moves `gear_factor` mm per commanded mm: not a track with a wrong gear ratio
    /// but frames in other units or of other skid positions.
    #[error(
        "the base moves {gear_factor:.6e} mm per commanded mm of skid (a track is within {tolerance} of 1): the frames are in other units than the skid, or the skid column is wrong"
    )]
    ImplausibleGear {
        /// Measured mm per commanded mm.
        gear_factor: f64,
        /// How far from 1 it may be.
        tolerance: f64,
    },
}

/// Everything that can go wrong in the track model, by cause.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TrackError {
    /// Writing an output file failed (nothing was left half-written).
    #[error(transparent)]
    Write(#[from] crate::output::OutputError),
    /// `D(s)` asked outside `[s_0, s_N]` with `extrapolate = "error"`.
    #[error(
        "skid {skid} mm is outside the profile's range [{min}, {max}] mm (measure further, or set extrapolate = \"clamp\" or \"linear\" in the profile)"
    )]
    OutOfRange {
        /// The skid asked for, mm.
        skid: f64,
        /// The first knot's skid, mm.
        min: f64,
        /// The last knot's skid, mm.
        max: f64,
    },
    /// A file could not be read or written.
    #[error("{}: {error}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        error: std::io::Error,
    },
    /// An input file (CSV table, profile) that is malformed at a known place.
    #[error("{0}")]
    Input(Box<LocatedError>),
    /// Knots given in code that cannot carry a spline (too few, not increasing, not finite).
    #[error("{context}: {error}")]
    Knots {
        /// What the knots are for.
        context: String,
        /// Why they carry no spline.
        error: SplineError,
    },
    /// The measurements of one skid position give no trustworthy base frame.
    #[error("skid {skid} mm: {problem}")]
    Skid {
        /// The skid position, mm.
        skid: f64,
        /// What is wrong with its points.
        problem: SkidProblem,
    },
    /// A point to leave out that no measurement row has.
    #[error("no point {point} at skid {skid} mm to exclude")]
    UnknownExclusion {
        /// The skid position asked for, mm.
        skid: f64,
        /// The point number asked for.
        point: u32,
    },
    /// The sampling frames give no straight nominal.
    #[error("{0}")]
    Nominal(NominalProblem),
    /// A noise level that is not a non-negative number.
    #[error("noise level {sigma} mm: give a non-negative number")]
    NoiseLevel {
        /// The level given, mm.
        sigma: f64,
    },
    /// The fits leave no degree of freedom to estimate the noise from.
    #[error(
        "{points} point(s) leave no residual to estimate the noise from: give the noise level, or measure more points"
    )]
    NoNoiseEstimate {
        /// Points measured.
        points: usize,
    },
    /// Knot uncertainties given in code that do not match the profile's knots one to one.
    #[error("{given} knot uncertainties for {knots} knots")]
    KnotUncertaintyCount {
        /// Uncertainties given.
        given: usize,
        /// Knots of the profile.
        knots: usize,
    },
    /// A scan the spectrum cannot use (too short, positions not increasing).
    #[error("{0}")]
    Scan(String),
    /// A figure or file could not be produced.
    #[error("{0}")]
    Output(String),
}

impl From<LocatedError> for TrackError {
    fn from(e: LocatedError) -> TrackError {
        TrackError::Input(Box::new(e))
    }
}

impl TrackError {
    /// The located input error, if this is one.
    pub fn located(&self) -> Option<&LocatedError> {
        match self {
            TrackError::Input(e) => Some(e),
            _ => None,
        }
    }
}
