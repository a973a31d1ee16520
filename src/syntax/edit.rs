//! Span-splice rewriting: replace only the bytes a transform changes.

use super::Span;

/// Replace the bytes of `span` in the original source with `text`.
///
/// 24 bytes: the span is kept as two `u32` offsets (trackfix reads no file of 4 GiB or more,
/// `output::MAX_INPUT_BYTES`; its parsers keep `u32` offsets too). A `correct` of a 20 MB
/// module holds 700,000 edits next to the whole model, and two `usize` offsets were 5.6 MB of
/// its peak. A span that does not fit is kept as a reversed one, which [`apply_edits`] refuses
/// as [`EditError::OutOfBounds`]: never an edit at another place.
#[derive(Clone, PartialEq, Eq)]
pub struct Edit {
    start: u32,
    end: u32,
    /// What the bytes of [`span`](Edit::span) become.
    pub text: EditText,
}

impl Edit {
    /// Replaces `span` with `text`.
    pub fn new(span: Span, text: impl Into<Vec<u8>>) -> Edit {
        Edit::with_text(span, EditText::from(text.into()))
    }

    /// Replaces `span` with `text`, already an [`EditText`].
    pub fn with_text(span: Span, text: EditText) -> Edit {
        let (start, end) = match (u32::try_from(span.start), u32::try_from(span.end)) {
            (Ok(start), Ok(end)) => (start, end),
            _ => (u32::MAX, 0),
        };
        Edit { start, end, text }
    }

    /// The bytes of the original source to replace (empty: insert at `span().start`).
    pub fn span(&self) -> Span {
        Span::new(self.start as usize, self.end as usize)
    }
}

/// With its span as a [`Span`]: `Edit { span: Span { start: 1, end: 4 }, text: [..] }`.
impl std::fmt::Debug for Edit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Edit")
            .field("span", &self.span())
            .field("text", &self.text)
            .finish()
    }
}

/// The bytes an [`Edit`] writes: up to 14 kept inline, longer ones on the heap.
///
/// Almost every edit is one number (`-1517.563`, `0.7071068`): a `correct` of a 20 MB module
/// holds 700,000 of them, next to the whole model, until the output is built, and a heap block
/// each was a fifth of its peak memory. 14 bytes hold every number trackfix writes at the
/// precisions it reads; a longer text sits behind a thin pointer, so an `EditText` is 16
/// bytes and an [`Edit`] 32 (it was 40 with 22 inline bytes: 5.6 MB of that peak).
/// Reads as a byte slice (`Deref<Target = [u8]>`).
#[derive(Clone, PartialEq, Eq)]
pub struct EditText(TextRepr);

const INLINE: usize = 14;

#[derive(Clone, PartialEq, Eq)]
enum TextRepr {
    Inline { len: u8, bytes: [u8; INLINE] },
    // Boxed twice: a thin pointer keeps the enum at 16 bytes.
    Heap(Box<Box<[u8]>>),
}

impl EditText {
    /// A copy of `text`: inline up to 14 bytes, so a written number costs no allocation.
    pub fn from_bytes(text: &[u8]) -> EditText {
        Self::inline(text).unwrap_or_else(|| EditText(TextRepr::Heap(Box::new(text.into()))))
    }

    fn inline(text: &[u8]) -> Option<EditText> {
        let n = text.len();
        // The length check keeps the conversion in range: `len as u8` ≤ 14.
        if n > INLINE {
            return None;
        }
        let mut bytes = [0; INLINE];
        bytes.get_mut(..n)?.copy_from_slice(text);
        Some(EditText(TextRepr::Inline {
            len: n as u8,
            bytes,
        }))
    }
}

impl From<Vec<u8>> for EditText {
    fn from(text: Vec<u8>) -> EditText {
        Self::inline(&text)
            .unwrap_or_else(|| EditText(TextRepr::Heap(Box::new(text.into_boxed_slice()))))
    }
}

impl std::ops::Deref for EditText {
    type Target = [u8];

    fn deref(&self) -> &[u8] {
        match &self.0 {
            TextRepr::Inline { len, bytes } => bytes.get(..*len as usize).unwrap_or(&[]),
            TextRepr::Heap(b) => b,
        }
    }
}

/// As a byte vector prints: `[49, 46, 53]`.
impl std::fmt::Debug for EditText {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.iter()).finish()
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
    order.sort_by_key(|e| (e.start, e.end));
    order.dedup_by(|b, a| (a.start, a.end) == (b.start, b.end) && a.text == b.text);
    // The exact size (edits checked below): the output of a large program is as large as its
    // source, and room to spare would be held for the rest of the run.
    let size = order.iter().fold(src.len(), |n, e| {
        let removed = e.end.saturating_sub(e.start) as usize;
        n.saturating_add(e.text.len()).saturating_sub(removed)
    });
    let mut out = Vec::with_capacity(size);
    let mut pos = 0;
    let mut prev: Option<Span> = None;
    for e in order {
        let span = e.span();
        if span.start > span.end || span.end > src.len() {
            return Err(EditError::OutOfBounds(span));
        }
        if span.start < pos {
            return Err(EditError::Overlap {
                first: prev.unwrap_or(span),
                second: span,
            });
        }
        out.extend_from_slice(&src[pos..span.start]);
        out.extend_from_slice(&e.text);
        pos = span.end;
        prev = Some(span);
    }
    out.extend_from_slice(&src[pos..]);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edit_text_reads_back_inline_and_on_the_heap() {
        assert_eq!(std::mem::size_of::<EditText>(), 16);
        assert_eq!(std::mem::size_of::<Edit>(), 24);
        for n in [0, 1, 13, 14, 15, 22, 23, 64] {
            let bytes: Vec<u8> = (0..n).map(|i| b'0' + (i % 10) as u8).collect();
            let t = EditText::from(bytes.clone());
            assert_eq!(&*t, bytes.as_slice(), "{n} bytes");
            assert_eq!(
                matches!(t.0, TextRepr::Inline { .. }),
                n <= INLINE,
                "{n} bytes"
            );
            assert_eq!(format!("{t:?}"), format!("{bytes:?}"));
        }
        // Equal texts are equal whatever they were built from.
        assert_eq!(
            Edit::new(Span::new(0, 1), "1.5"),
            Edit::new(Span::new(0, 1), b"1.5".to_vec())
        );
        assert_eq!(
            EditText::from_bytes(b"1.5"),
            EditText::from(b"1.5".to_vec())
        );
        let long = [b'7'; 40];
        assert_eq!(&*EditText::from_bytes(&long), &long[..]);
        assert_ne!(
            EditText::from(b"1.5".to_vec()),
            EditText::from(b"1.50".to_vec())
        );
    }

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
    fn spans_read_back_and_one_past_u32_is_refused_not_moved() {
        let e = Edit::new(Span::new(7, 12), "1.5");
        assert_eq!(e.span(), Span::new(7, 12));
        assert_eq!(
            format!("{e:?}"),
            "Edit { span: Span { start: 7, end: 12 }, text: [49, 46, 53] }"
        );
        let top = u32::MAX as usize;
        assert_eq!(
            Edit::new(Span::new(top, top), "x").span(),
            Span::new(top, top)
        );
        if let Some(past) = top.checked_add(1) {
            let e = Edit::new(Span::new(past, past), "x");
            assert!(e.span().start > e.span().end);
            assert_eq!(
                apply_edits(b"ab", &[e]),
                Err(EditError::OutOfBounds(Span::new(top, 0)))
            );
        }
    }

    #[test]
    fn identical_duplicates_collapse() {
        let e = Edit::new(Span::new(0, 1), "z");
        assert_eq!(apply_edits(b"ab", &[e.clone(), e]).unwrap(), b"zb");
    }
}
