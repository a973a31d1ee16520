//! Parser test data as files, as rust-analyzer's `test_data/parser/{ok,err}`: every input under
//! `tests/data/{rapid,krl}/{ok,err}/` has a committed `<name>.tree` next to it holding the one
//! tree dump of both languages (one line per node, whitespace included) and, for `err` inputs,
//! the located diagnostics. `ok` inputs must parse without a diagnostic, `err` inputs with at
//! least one; every input must print back byte for byte.
//!
//! After a deliberate parser change, `TRACKFIX_BLESS=1 cargo test --test it parser_data`
//! rewrites the `.tree` files; review them as diffs before committing.

use std::path::{Path, PathBuf};

use trackfix::syntax::{Diagnostic, LineIndex};
use trackfix::{krl, rapid};

use crate::support::root;

/// The inputs of one `tests/data/<language>/<ok|err>` folder, sorted.
fn inputs(language: &str, outcome: &str) -> Vec<PathBuf> {
    let dir = root().join("tests/data").join(language).join(outcome);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e != "tree"))
        .collect();
    files.sort();
    files
}

/// The dump of `src` parsed as `language`: the tree, then each diagnostic rendered.
fn dump(language: &str, path: &Path, src: &[u8]) -> (String, Vec<Diagnostic>, bool) {
    let (mut out, diagnostics, prints_back) = match language {
        "rapid" => {
            let p = rapid::parse_tree(src);
            assert_eq!(p.round_trip, p.tree.prints_back(src), "{}", path.display());
            (p.tree.dump(src), p.diagnostics, p.tree.prints_back(src))
        }
        _ => {
            let p = krl::parse(src);
            assert_eq!(p.round_trip, p.tree.prints_back(src), "{}", path.display());
            (p.tree.dump(src), p.diagnostics, p.tree.prints_back(src))
        }
    };
    let shown = path
        .strip_prefix(root())
        .unwrap_or(path)
        .display()
        .to_string()
        .replace('\\', "/");
    let lines = LineIndex::new(src);
    for d in &diagnostics {
        out.push('\n');
        out.push_str(&d.render(&shown, src, &lines));
    }
    (out, diagnostics, prints_back)
}

fn check(language: &str, outcome: &str) {
    let bless = std::env::var_os("TRACKFIX_BLESS").is_some();
    let files = inputs(language, outcome);
    assert!(!files.is_empty(), "no test data for {language}/{outcome}");
    let mut stale = Vec::new();
    for path in files {
        let src = std::fs::read(&path).unwrap();
        let (actual, diagnostics, prints_back) = dump(language, &path, &src);
        assert!(prints_back, "{} does not print back", path.display());
        match outcome {
            "ok" => assert!(
                diagnostics.is_empty(),
                "{} should parse cleanly:\n{actual}",
                path.display()
            ),
            _ => assert!(
                !diagnostics.is_empty(),
                "{} should report an error",
                path.display()
            ),
        }
        let expected_path = path.with_extension("tree");
        if bless {
            std::fs::write(&expected_path, &actual).unwrap();
            continue;
        }
        match std::fs::read_to_string(&expected_path) {
            Ok(expected) if expected == actual => {}
            Ok(expected) => stale.push(format!(
                "{}:\n{}",
                expected_path.display(),
                similar::TextDiff::from_lines(&expected, &actual)
                    .unified_diff()
                    .header("committed", "parsed")
            )),
            Err(_) => stale.push(format!("{} is missing", expected_path.display())),
        }
    }
    assert!(
        stale.is_empty(),
        "tree dumps differ (TRACKFIX_BLESS=1 rewrites them):\n{}",
        stale.join("\n")
    );
}

#[test]
fn rapid_ok() {
    check("rapid", "ok");
}

#[test]
fn rapid_err() {
    check("rapid", "err");
}

#[test]
fn krl_ok() {
    check("krl", "ok");
}

#[test]
fn krl_err() {
    check("krl", "err");
}

/// A stray control byte in a comment (the `0x05`/`0x1C` of the Latin-1 and `CONFIRM` inputs)
/// does not make a program file "binary": the loader reads it as text.
#[test]
fn control_bytes_in_comments_are_text() {
    for name in ["rapid/ok/latin1_identifiers.mod", "krl/ok/confirm.src"] {
        let path = root().join("tests/data").join(name);
        let bytes = std::fs::read(&path).unwrap();
        assert!(bytes.iter().any(|&b| b == 0x05 || b == 0x1C), "{name}");
        let read = trackfix::program::read_source(&path, &Default::default()).unwrap();
        assert_eq!(read[..], bytes[..]);
    }
}

/// What the inputs are there for (constructs once misparsed), checked on the parse itself and
/// not only on the dump: the names and declarations come out as the grammar says.
#[test]
fn parser_gaps_are_closed() {
    let read = |name: &str| std::fs::read(root().join("tests/data").join(name)).unwrap();
    // `GLOBAL INT x = 10`: a declaration of `part_count`, not an opaque line.
    let src = read("krl/ok/global_simple_types.dat");
    let p = krl::parse(&src);
    let decl_names: Vec<String> = p
        .stmts
        .iter()
        .filter_map(|s| match &s.kind {
            krl::StmtKind::Decl { vars, .. } => {
                Some(String::from_utf8_lossy(vars[0].name.slice(&src)).into_owned())
            }
            _ => None,
        })
        .collect();
    assert_eq!(
        decl_names,
        ["part_count", "gain", "homed", "XPark", "other"]
    );
    // `DEFFCT CHAR[32] label(…)`: the routine is named `label`.
    let src = read("krl/ok/array_return_type.src");
    let p = krl::parse(&src);
    let routines: Vec<String> = p
        .stmts
        .iter()
        .filter_map(|s| match &s.kind {
            krl::StmtKind::Routine { name: Some(n), .. } => {
                Some(String::from_utf8_lossy(n.slice(&src)).into_owned())
            }
            _ => None,
        })
        .collect();
    assert_eq!(routines, ["caller", "label"]);
    // `PROC Ñandú()`: one routine, its Latin-1 name one identifier; the target `pÑ` is found.
    let path = root().join("tests/data/rapid/ok/latin1_identifiers.mod");
    let file = rapid::parse_file(&path, std::fs::read(&path).unwrap());
    assert!(file.diagnostics.is_empty(), "{:?}", file.diagnostics);
    assert_eq!(file.positions.len(), 1);
    assert_eq!(file.position(0).unwrap().name.as_deref(), Some("p\u{d1}"));
}

/// The README's Rust example is the doc test in `src/syntax/lossless_example.md` (its lines
/// without rustdoc's hidden `# ` lines), so the example a reader copies compiles and runs.
#[test]
fn readme_example_is_this_doc_test() {
    let rust_block = |text: &str| -> Vec<String> {
        let start = text.find("```rust\n").expect("a ```rust block") + "```rust\n".len();
        let len = text[start..].find("```").expect("its end");
        text[start..start + len]
            .lines()
            .filter(|l| !l.starts_with("# "))
            .map(str::to_owned)
            .collect()
    };
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let doc = std::fs::read_to_string(root().join("src/syntax/lossless_example.md")).unwrap();
    assert_eq!(rust_block(&readme), rust_block(&doc));
    assert_eq!(rust_block(&doc).len(), 2);
}

/// `report::errors` (what a transform checks before it writes, without decoding a position) is
/// exactly the errors among `report::lints`, for every test input: broken ones with errors, and
/// clean ones whose positions give warnings and notes.
#[test]
fn errors_are_the_errors_among_the_lints() {
    use trackfix::syntax::Severity;
    let mut with_errors = 0;
    for language in ["rapid", "krl"] {
        for outcome in ["ok", "err"] {
            for path in inputs(language, outcome) {
                let src = std::fs::read(&path).unwrap();
                let file = match language {
                    "rapid" => rapid::parse_file(&path, src),
                    _ => krl::parse_file(&path, src),
                };
                let from_lints: Vec<Diagnostic> = trackfix::report::lints(&file)
                    .into_iter()
                    .filter(|d| d.severity == Severity::Error)
                    .collect();
                let errors = trackfix::report::errors(&file);
                assert_eq!(
                    format!("{errors:?}"),
                    format!("{from_lints:?}"),
                    "{}",
                    path.display()
                );
                with_errors += usize::from(!errors.is_empty());
            }
        }
    }
    assert!(
        with_errors > 0,
        "no input with errors: the comparison tests nothing"
    );
}
