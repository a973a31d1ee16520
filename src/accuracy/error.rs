//! What goes wrong in an accuracy analysis, as data: a location in an input file with the line
//! and what to do, or a reason the measurements cannot give the figures. Rendered only when
//! displayed (`file:line:col: error: …`, the line, a caret, `= help: …`).

use std::fmt;
use std::path::PathBuf;

/// A place in an input file: the message, the line as written and a caret under the field.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Located {
    pub path: PathBuf,
    /// 1-based line.
    pub line: u64,
    /// 1-based column (in characters of the line) of the first character the caret marks.
    pub column: usize,
    /// How many characters the caret covers (at least 1).
    pub width: usize,
    /// The line as written, without its line break.
    pub line_text: String,
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
        path: PathBuf,
        #[source]
        error: std::io::Error,
    },
    /// Bad input at a place in a file.
    #[error("{0}")]
    Input(Box<Located>),
    /// The measurements, taken together, cannot give the figures (the message says why and
    /// what to measure).
    #[error("{0}")]
    Invalid(String),
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
