//! `-q`/`-v` and the grouping of repeated messages, shared by `check` and the transforms: a
//! batch of 1,000 modules with one warning each must not print 6,000 lines, and the person
//! who wants them all asks with `-v`.

use std::collections::BTreeMap;
use std::io::Write;

use trackfix::syntax::Severity;

/// How much a command prints (the flags, flattened into each command's arguments).
#[derive(clap::Args, Clone, Copy, Debug, Default)]
pub(crate) struct Verbosity {
    /// Print errors only: no per-file lines, warnings or notes.
    #[arg(short, long, conflicts_with = "verbose")]
    pub(crate) quiet: bool,
    /// Print every warning and note (repeated ones are otherwise shown 3 times, then counted).
    #[arg(short, long)]
    pub(crate) verbose: bool,
}

/// How many messages of one kind are shown before the rest are counted (unless `-v`).
const SHOWN_PER_KIND: usize = 3;

/// Prints messages with repeats grouped: the first few of each kind, then a count.
pub(super) struct Messages {
    verbosity: Verbosity,
    /// Nothing at all is printed (the command writes JSON instead).
    silent: bool,
    seen: BTreeMap<(Severity, String), usize>,
}

impl Messages {
    /// Messages grouped by kind (a refusal kind's name, a finding's [`shape`]), which the
    /// count line names; `silent`: print nothing (the command writes JSON instead).
    pub(super) fn new(verbosity: Verbosity, silent: bool) -> Messages {
        Messages {
            verbosity,
            silent,
            seen: BTreeMap::new(),
        }
    }

    /// Shows `text` as a line unless quiet (errors always), silent, or the kind was shown often enough.
    pub(super) fn show(
        &mut self,
        w: &mut impl Write,
        severity: Severity,
        kind: &str,
        text: &dyn std::fmt::Display,
    ) -> std::io::Result<()> {
        if self.silent || (self.verbosity.quiet && severity < Severity::Error) {
            return Ok(());
        }
        let n = self.seen.entry((severity, kind.to_owned())).or_default();
        *n += 1;
        if *n <= SHOWN_PER_KIND || self.verbosity.verbose {
            writeln!(w, "{text}")?;
        }
        Ok(())
    }

    /// The counts of what was not shown.
    pub(super) fn finish(&self, w: &mut impl Write) -> std::io::Result<()> {
        if self.verbosity.verbose {
            return Ok(());
        }
        for ((severity, kind), n) in &self.seen {
            if *n > SHOWN_PER_KIND {
                writeln!(
                    w,
                    "{}: … and {} more like this [{kind}] (-v shows all)",
                    severity.as_str(),
                    n - SHOWN_PER_KIND
                )?;
            }
        }
        Ok(())
    }
}

/// A message with what varies between its instances (quoted names, numbers) blanked: the key
/// under which `check` groups repeated findings, so 500 `quaternion of `pN` is not normalised
/// (|q| = …)` are one kind.
pub(super) fn shape(message: &str) -> String {
    let mut out = String::with_capacity(message.len());
    let mut quoted = false;
    let mut in_number = false;
    for c in message.chars() {
        if c == '`' {
            quoted = !quoted;
            if quoted {
                out.push_str("`…`");
            }
            in_number = false;
            continue;
        }
        if quoted {
            continue;
        }
        if c.is_ascii_digit() || (in_number && c == '.') {
            if !in_number {
                out.push('…');
            }
            in_number = true;
            continue;
        }
        in_number = false;
        out.push(c);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shape_blanks_names_and_numbers() {
        assert_eq!(
            shape("quaternion of `p12` is not normalised (|q| = 1.020000)"),
            "quaternion of `…` is not normalised (|q| = …)"
        );
        assert_eq!(
            shape("quaternion of `pHome` is not normalised (|q| = 0.5)"),
            shape("quaternion of `p7` is not normalised (|q| = 3)")
        );
        assert_ne!(shape("expected `;`"), shape("expected an expression"));
    }

    fn shown(verbosity: Verbosity, n: usize, severity: Severity) -> String {
        let mut m = Messages::new(verbosity, false);
        let mut w = Vec::new();
        for i in 0..n {
            m.show(&mut w, severity, "k", &format!("m{i}")).unwrap();
        }
        m.finish(&mut w).unwrap();
        String::from_utf8(w).unwrap()
    }

    #[test]
    fn three_of_a_kind_then_a_count_unless_verbose_or_quiet() {
        let default = Verbosity::default();
        assert_eq!(
            shown(default, 5, Severity::Warning),
            "m0\nm1\nm2\nwarning: … and 2 more like this [k] (-v shows all)\n"
        );
        assert_eq!(shown(default, 3, Severity::Warning), "m0\nm1\nm2\n");
        let verbose = Verbosity {
            verbose: true,
            ..default
        };
        assert_eq!(shown(verbose, 5, Severity::Warning), "m0\nm1\nm2\nm3\nm4\n");
        let quiet = Verbosity {
            quiet: true,
            ..default
        };
        assert_eq!(shown(quiet, 5, Severity::Warning), "");
        assert_eq!(
            shown(quiet, 4, Severity::Error),
            "m0\nm1\nm2\nerror: … and 1 more like this [k] (-v shows all)\n"
        );
    }
}
