//! The library speaks in its own terms: outside the command line (`src/cli/`, `src/main.rs`) no
//! message, help text or documentation names a command-line flag, so a library caller never
//! reads advice about options it does not have (docs/design.md §8, errors that render
//! themselves). Plain `//` comments are notes to the reader of the code and are not checked.

use std::path::Path;

use crate::support::{files_under, root};

/// Byte offsets of `--` followed by a lower-case letter, not preceded by another `-` (so a
/// unified diff's `--- a/x` header is no flag).
fn flag_names(line: &str) -> Vec<usize> {
    let b = line.as_bytes();
    (0..b.len().saturating_sub(2))
        .filter(|&i| {
            b[i] == b'-'
                && b[i + 1] == b'-'
                && b[i + 2].is_ascii_lowercase()
                && (i == 0 || b[i - 1] != b'-')
        })
        .collect()
}

#[test]
fn flag_names_finds_flags_and_nothing_else() {
    assert_eq!(flag_names("use `--in-place` here"), [5]);
    assert_eq!(flag_names("\"see --help\""), [5]);
    assert!(flag_names("--- a/file.mod").is_empty());
    assert!(flag_names("x -= 1; y--;").is_empty());
    assert!(flag_names("-o FILE").is_empty());
}

#[test]
fn library_text_names_no_command_line_flag() {
    let src = root().join("src");
    let mut files = files_under(&src);
    files.retain(|path| path.extension().is_some_and(|e| e == "rs"));
    assert!(
        files.len() > 50,
        "found only {} files under src/",
        files.len()
    );
    let mut found = Vec::new();
    for path in files {
        let rel = path.strip_prefix(&src).unwrap();
        if rel.starts_with("cli") || rel == Path::new("main.rs") {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        for (n, line) in text.lines().enumerate() {
            let code = line.trim_start();
            let plain_comment =
                code.starts_with("//") && !code.starts_with("///") && !code.starts_with("//!");
            if !plain_comment && !flag_names(line).is_empty() {
                found.push(format!("src/{}:{}: {}", rel.display(), n + 1, code));
            }
        }
    }
    assert!(
        found.is_empty(),
        "library text names command-line flags (say what the caller does instead):\n{}",
        found.join("\n")
    );
}
