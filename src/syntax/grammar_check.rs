//! Test support: ties a grammar file (`grammars/*.ebnf`) to the code that implements it, so
//! that neither can change without the other (rust-analyzer generates its parser's kinds from
//! `rust.ungram`; trackfix checks instead).
//!
//! A function cites the rules it implements in its doc comment, either by writing the rule out
//! (`` `name = …` ``) or by naming it (``Rule `name` ``, ``Rules `a`, `b` and `c` ``).

use std::collections::BTreeSet;

/// The grammar without its `(* … *)` comments.
fn strip_comments(ebnf: &str) -> String {
    let mut out = String::with_capacity(ebnf.len());
    let mut rest = ebnf;
    while let Some(i) = rest.find("(*") {
        out.push_str(&rest[..i]);
        rest = rest[i..].find("*)").map_or("", |j| &rest[i + j + 2..]);
    }
    out.push_str(rest);
    out
}

fn is_name(s: &str) -> bool {
    s.chars()
        .next()
        .is_some_and(|c| c.is_ascii_lowercase() || c == '_')
        && s.chars()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
}

/// Every rule the grammar defines (`name = …` at the start of a line).
pub(crate) fn rules(ebnf: &str) -> BTreeSet<String> {
    strip_comments(ebnf)
        .lines()
        .filter_map(|l| {
            let (name, rest) = l.split_once('=')?;
            let name = name.trim();
            (l.starts_with(name) && is_name(name) && !rest.starts_with('='))
                .then(|| name.to_owned())
        })
        .collect()
}

/// The quoted terminals in the body of `rule` (up to its closing `;`).
pub(crate) fn terminals(ebnf: &str, rule: &str) -> BTreeSet<String> {
    let text = strip_comments(ebnf);
    let Some(start) = text.lines().position(|l| {
        l.split_once('=')
            .is_some_and(|(n, _)| n.trim() == rule && l.starts_with(rule))
    }) else {
        return BTreeSet::new();
    };
    let mut body = String::new();
    for l in text.lines().skip(start) {
        body.push_str(l);
        body.push('\n');
        if l.trim_end().ends_with(';') {
            break;
        }
    }
    let body = body.split_once('=').map_or("", |(_, b)| b);
    body.split('"')
        .skip(1)
        .step_by(2)
        .map(str::to_owned)
        .collect()
}

/// Every rule cited in the doc comments of `sources`.
pub(crate) fn citations(sources: &[&str]) -> BTreeSet<String> {
    // Each doc comment as one line, so a list of rules may wrap.
    let mut blocks: Vec<String> = Vec::new();
    let mut open = false;
    for line in sources.iter().flat_map(|s| s.lines()) {
        match line.trim_start().strip_prefix("///") {
            Some(text) => {
                if !open {
                    blocks.push(String::new());
                    open = true;
                }
                if let Some(block) = blocks.last_mut() {
                    block.push(' ');
                    block.push_str(text.trim());
                }
            }
            None => open = false,
        }
    }
    let mut cited = BTreeSet::new();
    for comment in &blocks {
        // `name = …`: the rule written out.
        for (i, _) in comment.match_indices('`') {
            let after = &comment[i + 1..];
            if let Some((name, _)) = after.split_once(" =")
                && is_name(name)
                && !after[name.len() + 2..].starts_with('=')
            {
                cited.insert(name.to_owned());
            }
        }
        // Rule `name`, Rules `a`, `b` and `c`.
        for marker in ["Rule `", "Rules `", "rule `", "rules `"] {
            for (i, _) in comment.match_indices(marker) {
                let mut rest = &comment[i + marker.len() - 1..];
                while let Some(r) = rest.strip_prefix('`') {
                    let Some((name, after)) = r.split_once('`') else {
                        break;
                    };
                    if is_name(name) {
                        cited.insert(name.to_owned());
                    }
                    rest = after
                        .strip_prefix(", ")
                        .or_else(|| after.strip_prefix(",  "))
                        .or_else(|| after.strip_prefix(" and "))
                        .or_else(|| after.strip_prefix(", and "))
                        .unwrap_or("");
                }
            }
        }
    }
    cited
}

/// Reads a file of the package (for the grammar checks of each language).
pub(crate) fn read(path: &str) -> String {
    let full = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
    std::fs::read_to_string(&full).unwrap_or_else(|e| panic!("{}: {e}", full.display()))
}

/// Asserts that the grammar's rules and the rules `sources` cite are the same set.
pub(crate) fn assert_rules_cited(grammar: &str, sources: &[&str]) {
    let ebnf = read(grammar);
    let texts: Vec<String> = sources.iter().map(|s| read(s)).collect();
    let texts: Vec<&str> = texts.iter().map(String::as_str).collect();
    let defined = rules(&ebnf);
    let cited = citations(&texts);
    let uncited: Vec<_> = defined.difference(&cited).collect();
    let unknown: Vec<_> = cited.difference(&defined).collect();
    assert!(
        uncited.is_empty() && unknown.is_empty(),
        "{grammar}: rules no function cites: {uncited:?}; rules cited but not in the grammar: {unknown:?}"
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_rules_terminals_and_citations() {
        let g = "(* a = not a rule *)\nfile = { item } ;\nitem = \"A\" | \"B\"\n     | \"C\" ;\nx == y\n";
        assert_eq!(rules(g), BTreeSet::from(["file".into(), "item".into()]));
        assert_eq!(
            terminals(g, "item"),
            BTreeSet::from(["A".into(), "B".into(), "C".into()])
        );
        let src = "/// `file = { item }`\n/// Rules `item`, `b` and `c`: x\n// `notdoc = 1`\n/// `x == y`";
        assert_eq!(
            citations(&[src]),
            BTreeSet::from(["file".into(), "item".into(), "b".into(), "c".into()])
        );
    }
}
