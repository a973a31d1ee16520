//! Span-splice rewriting: replace only the bytes a transform changes.

use super::Span;

/// Replace the bytes of `span` in the original source with `text`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Edit {
    /// The bytes of the original source to replace (empty: insert at `span.start`).
    pub span: Span,
    /// What they become.
    pub text: Vec<u8>,
}

impl Edit {
    /// Replaces `span` with `text`.
    pub fn new(span: Span, text: impl Into<Vec<u8>>) -> Edit {
        Edit {
            span,
            text: text.into(),
        }
    }
}

/// Why a set of edits cannot be applied. Either is a bug of the transform that made the edits,
/// not of the input.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum EditError {
    /// Two edits touch the same bytes.
    #[error("edits overlap at bytes {first:?} and {second:?}")]
    Overlap {
        /// The span of the earlier edit.
        first: Span,
        /// The span of the edit that overlaps it.
        second: Span,
    },
    /// An edit's span is reversed or ends past the source.
    #[error("edit at bytes {0:?} lies outside the source")]
    OutOfBounds(Span),
}

/// Applies non-overlapping edits to `src`; everything outside their spans is copied unchanged.
///
/// Edits may come in any order. Two edits of the same span with the same text count as one (a
/// target referenced twice is rewritten once); any other overlap is an error rather than a guess.
pub fn apply_edits(src: &[u8], edits: &[Edit]) -> Result<Vec<u8>, EditError> {
    let mut order: Vec<&Edit> = edits.iter().collect();
    order.sort_by_key(|e| (e.span.start, e.span.end));
    order.dedup_by(|b, a| a.span == b.span && a.text == b.text);
    let mut out = Vec::with_capacity(src.len() + 16 * order.len());
    let mut pos = 0;
    let mut prev: Option<Span> = None;
    for e in order {
        if e.span.start > e.span.end || e.span.end > src.len() {
            return Err(EditError::OutOfBounds(e.span));
        }
        if e.span.start < pos {
            return Err(EditError::Overlap {
                first: prev.unwrap_or(e.span),
                second: e.span,
            });
        }
        out.extend_from_slice(&src[pos..e.span.start]);
        out.extend_from_slice(&e.text);
        pos = e.span.end;
        prev = Some(e.span);
    }
    out.extend_from_slice(&src[pos..]);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splices_in_any_order() {
        let src = b"[1,2,3]";
        let out = apply_edits(
            src,
            &[
                Edit::new(Span::new(5, 6), "30.000"),
                Edit::new(Span::new(1, 2), "-1"),
            ],
        )
        .unwrap();
        assert_eq!(out, b"[-1,2,30.000]");
    }

    #[test]
    fn rejects_overlap_and_out_of_bounds() {
        let src = b"abcdef";
        assert!(matches!(
            apply_edits(
                src,
                &[
                    Edit::new(Span::new(0, 3), "x"),
                    Edit::new(Span::new(2, 4), "y")
                ]
            ),
            Err(EditError::Overlap { .. })
        ));
        assert!(matches!(
            apply_edits(src, &[Edit::new(Span::new(4, 9), "x")]),
            Err(EditError::OutOfBounds(_))
        ));
    }

    #[test]
    fn identical_duplicates_collapse() {
        let e = Edit::new(Span::new(0, 1), "z");
        assert_eq!(apply_edits(b"ab", &[e.clone(), e]).unwrap(), b"zb");
    }
}
