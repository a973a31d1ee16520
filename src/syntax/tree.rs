//! The lossless syntax tree shared by every robot language.
//!
//! A language plugs in through [`Language`] (its node kinds and which of them are branches), in
//! the spirit of rowan's `Language` trait. The layout is one vector of [`Node`]s in pre-order,
//! the root first. Leaves own bytes of the source (a statement, a line, a run of trivia);
//! branches (a module, a routine, a block) only group the nodes up to their `subtree_end`.
//! Printing concatenates the leaves in order, so the round trip is checked, not assumed: a leaf
//! that is lost, duplicated or out of place shows as a difference in [`Tree::prints_back`].
//!
//! Parsers build trees with a [`TreeBuilder`] and hand what they read to a [`Sink`].

use std::fmt;

use super::{Diagnostic, Span};

/// A language's node kinds, as the shared tree needs them.
pub trait Language: 'static {
    /// The language's node kind enum.
    type Kind: Copy + fmt::Debug + Eq;
    /// The kind of the root branch.
    const ROOT: Self::Kind;
    /// The kind the builder gives to bytes between two leaves (whitespace and comments).
    const GAP: Self::Kind;
    /// True for kinds that group children instead of owning bytes.
    fn is_branch(kind: Self::Kind) -> bool;
}

/// Declares a language of the shared tree: the marker type, its [`Language`] impl (root, gap and
/// branch kinds), `NodeKind::is_branch`, and the `Node`/`Tree` aliases of the language's module.
/// A language's `tree.rs` is then its node kinds and this one line.
macro_rules! language {
    ($(#[$meta:meta])* $lang:ident: $kind:ident, root $root:ident, gap $gap:ident,
     branches [$($branch:ident),+ $(,)?]) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum $lang {}

        impl $crate::syntax::Language for $lang {
            type Kind = $kind;
            const ROOT: $kind = $kind::$root;
            const GAP: $kind = $kind::$gap;
            fn is_branch(kind: $kind) -> bool {
                kind.is_branch()
            }
        }

        impl $kind {
            /// True for kinds that group children instead of owning bytes.
            pub fn is_branch(self) -> bool {
                matches!(self, $($kind::$branch)|+)
            }
        }

        /// One node of this language's tree.
        pub type Node = $crate::syntax::Node<$kind>;

        /// A parsed source of this language: nodes in pre-order, the root first.
        pub type Tree = $crate::syntax::Tree<$lang>;
    };
}
pub(crate) use language;

/// One node: its kind, its bytes, and (for branches) where its subtree ends in [`Tree::nodes`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Node<K> {
    /// What the node is; the language's kind enum.
    pub kind: K,
    /// The node's first byte in the source.
    pub start: u32,
    /// One past its last byte.
    pub end: u32,
    /// Index one past this node's last descendant (`self + 1` for a leaf).
    pub subtree_end: u32,
}

impl<K> Node<K> {
    /// `start..end` as a [`Span`].
    pub fn span(&self) -> Span {
        Span::new(self.start as usize, self.end.max(self.start) as usize)
    }
}

/// A parsed source: nodes in pre-order, the root first.
pub struct Tree<L: Language> {
    /// Every node, in pre-order (`docs/design.md §12`).
    pub nodes: Vec<Node<L::Kind>>,
}

impl<L: Language> Clone for Tree<L> {
    fn clone(&self) -> Self {
        Tree {
            nodes: self.nodes.clone(),
        }
    }
}

impl<L: Language> fmt::Debug for Tree<L> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Tree").field("nodes", &self.nodes).finish()
    }
}

impl<L: Language> Default for Tree<L> {
    fn default() -> Self {
        Tree { nodes: Vec::new() }
    }
}

impl<L: Language> PartialEq for Tree<L> {
    fn eq(&self, other: &Self) -> bool {
        self.nodes == other.nodes
    }
}

impl<L: Language> Eq for Tree<L> {}

impl<L: Language> Tree<L> {
    /// The bytes of a node (for a branch, everything its subtree covers).
    pub fn node_span(&self, node: &Node<L::Kind>) -> Span {
        node.span()
    }

    /// The leaves in order: together they are the source.
    pub fn leaves(&self) -> impl Iterator<Item = &Node<L::Kind>> {
        self.nodes.iter().filter(|n| !L::is_branch(n.kind))
    }

    /// The source again, from the leaves. Equal to the input for every input.
    pub fn print(&self, src: &[u8]) -> Vec<u8> {
        let mut out = Vec::with_capacity(src.len());
        for n in self.leaves() {
            out.extend_from_slice(n.span().slice(src));
        }
        out
    }

    /// Writes the leaves in order to `out` (printing a large file without a second copy).
    pub fn write_to(&self, src: &[u8], out: &mut impl std::io::Write) -> std::io::Result<()> {
        for n in self.leaves() {
            out.write_all(n.span().slice(src))?;
        }
        Ok(())
    }

    /// True if printing gives `src` back, compared leaf by leaf without building the copy.
    pub fn prints_back(&self, src: &[u8]) -> bool {
        let mut pos = 0usize;
        for n in self.leaves() {
            let text = n.span().slice(src);
            if n.start as usize != pos && src.get(pos..pos + text.len()) != Some(text) {
                return false;
            }
            pos += text.len();
        }
        pos == src.len()
    }

    /// One line per node, indented by depth: kind, byte range and (for leaves) the text with
    /// control bytes escaped, whitespace included. The one dump format of every language, for
    /// snapshot tests and `tests/data`, in the spirit of rust-analyzer's test data.
    pub fn dump(&self, src: &[u8]) -> String {
        let mut out = String::new();
        let mut stack: Vec<u32> = Vec::new();
        for (i, n) in self.nodes.iter().enumerate() {
            while stack.last().is_some_and(|&end| end as usize <= i) {
                stack.pop();
            }
            out.push_str(&"  ".repeat(stack.len()));
            out.push_str(&format!("{:?}@{}..{}", n.kind, n.start, n.end));
            if L::is_branch(n.kind) {
                stack.push(n.subtree_end);
            } else {
                out.push(' ');
                out.push_str(&escape(n.span().slice(src)));
            }
            out.push('\n');
        }
        out
    }
}

/// Builds a [`Tree`] in pre-order: branches are opened and closed around their children, and
/// bytes between two leaves become a [`Language::GAP`] leaf, so every byte lands in exactly one
/// leaf.
///
/// A builder made by [`TreeBuilder::verifying`] keeps no nodes: it only checks, leaf by leaf,
/// that the leaves cover the source in order. Loading a program needs that answer (a file that
/// does not print back is never rewritten) but not the tree, which on a large module is 0.4
/// times the file while the positions are being read.
pub(crate) struct TreeBuilder<L: Language> {
    /// The nodes, when kept.
    nodes: Vec<Node<L::Kind>>,
    keeps: Keeps<L>,
    /// Nodes pushed so far (when nodes are kept, only those kept): the index the next node
    /// gets.
    count: u32,
    /// End of the last leaf pushed.
    leaf_end: u32,
    /// Every leaf so far started where the one before it ended.
    in_order: bool,
}

/// Which nodes a [`TreeBuilder`] keeps.
enum Keeps<L: Language> {
    /// Every node: the whole tree.
    All,
    /// Every branch and the leaves the function takes, no gap ([`TreeBuilder::skeleton`]):
    /// gaps are most of a file's leaves, and not asked of the function one by one.
    Skeleton(fn(L::Kind) -> bool),
    /// None ([`TreeBuilder::verifying`]).
    Nothing,
}

/// What a [`TreeBuilder`] built: the tree (empty for a verifying builder) and whether its
/// leaves cover the source exactly, in order.
pub(crate) struct Built<L: Language> {
    pub(crate) tree: Tree<L>,
    pub(crate) round_trip: bool,
}

impl<L: Language> TreeBuilder<L> {
    /// A builder with room for `capacity` nodes, the root opened.
    pub(crate) fn with_capacity(capacity: usize) -> TreeBuilder<L> {
        let mut nodes = Vec::with_capacity(capacity.max(1));
        nodes.push(Node {
            kind: L::ROOT,
            start: 0,
            end: 0,
            subtree_end: 1,
        });
        TreeBuilder {
            nodes,
            keeps: Keeps::All,
            count: 1,
            leaf_end: 0,
            in_order: true,
        }
    }

    /// A builder that keeps no nodes and only checks the round trip (see the type).
    pub(crate) fn verifying() -> TreeBuilder<L> {
        TreeBuilder {
            nodes: Vec::new(),
            keeps: Keeps::Nothing,
            count: 1,
            leaf_end: 0,
            in_order: true,
        }
    }

    /// A builder that keeps every branch and only the leaves `keep_leaf` takes, no gap: a tree that
    /// does not print back, for a reader that walks a few kinds of statements and need not
    /// hold a node per gap and declaration (indices are of the nodes kept). The round trip is
    /// still checked over every leaf.
    pub(crate) fn skeleton(keep_leaf: fn(L::Kind) -> bool) -> TreeBuilder<L> {
        TreeBuilder {
            keeps: Keeps::Skeleton(keep_leaf),
            ..TreeBuilder::with_capacity(16)
        }
    }

    /// Number of nodes so far: the index the next node gets.
    pub(crate) fn len(&self) -> usize {
        self.count as usize
    }

    /// Pushes a branch, or a leaf the builder keeps ([`TreeBuilder::push_leaf`]).
    #[inline]
    fn push(&mut self, kind: L::Kind, start: u32, end: u32) {
        if !matches!(self.keeps, Keeps::Nothing) {
            self.nodes.push(Node {
                kind,
                start,
                end,
                subtree_end: self.count + 1,
            });
        }
        self.count += 1;
    }

    /// Pushes a leaf, unless the builder is a skeleton's that does not keep its kind.
    #[inline]
    fn push_leaf(&mut self, kind: L::Kind, start: u32, end: u32) {
        match self.keeps {
            Keeps::Skeleton(keep_leaf) if !keep_leaf(kind) => {}
            _ => self.push(kind, start, end),
        }
    }

    /// Pushes the bytes from the last leaf up to `upto` as a gap leaf, if there are any.
    #[inline]
    pub(crate) fn gap(&mut self, upto: u32) {
        if upto > self.leaf_end {
            if !matches!(self.keeps, Keeps::Skeleton(_)) {
                self.push(L::GAP, self.leaf_end, upto);
            }
            self.leaf_end = upto;
        }
    }

    /// Pushes a leaf of bytes `start..end` (after the gap before it). (Always inlined: each
    /// parser's line loop calls it for nearly every statement.)
    #[inline(always)]
    pub(crate) fn leaf(&mut self, kind: L::Kind, start: u32, end: u32) {
        let end = end.max(start);
        self.gap(start);
        // After the gap the leaf starts at the last one's end, unless it starts before it:
        // bytes the tree would print twice.
        self.in_order &= start == self.leaf_end;
        self.push_leaf(kind, start, end);
        self.leaf_end = end;
    }

    /// Opens a branch at `start`; returns its index for [`TreeBuilder::close`].
    #[inline]
    pub(crate) fn open(&mut self, kind: L::Kind, start: u32) -> usize {
        self.gap(start);
        let idx = self.count as usize;
        self.push(kind, start, start);
        idx
    }

    /// Closes the branch opened at `idx`: it covers every node pushed since.
    #[inline]
    pub(crate) fn close(&mut self, idx: usize) {
        let len = self.count;
        let end = self.leaf_end;
        if let Some(n) = self.nodes.get_mut(idx) {
            n.subtree_end = len;
            n.end = end.max(n.start);
        }
    }

    /// The tree: the bytes up to `src_len` after the last leaf become a gap, the root closed.
    pub(crate) fn finish(mut self, src_len: u32) -> Built<L> {
        self.gap(src_len);
        self.close(0);
        Built {
            round_trip: self.in_order && self.leaf_end == src_len,
            tree: Tree { nodes: self.nodes },
        }
    }
}

/// Receives what a parser reads (statements, events), as toml_parser's receivers do: one parser
/// feeds several consumers. Any `FnMut(E)` closure is a sink.
pub trait Sink<E> {
    /// Takes one event, in source order.
    fn accept(&mut self, event: E);
}

impl<E, F: FnMut(E)> Sink<E> for F {
    #[inline]
    fn accept(&mut self, event: E) {
        self(event)
    }
}

/// A sink that keeps nothing: parsing for the tree alone.
pub struct NoSink;

impl<E> Sink<E> for NoSink {
    #[inline]
    fn accept(&mut self, _: E) {}
}

/// The one size guard of every parser: spans are `u32`, so a source longer than `u32::MAX`
/// bytes is reported, not parsed. `None` when `src` fits.
pub(crate) fn too_large(src: &[u8]) -> Option<Diagnostic> {
    (src.len() > u32::MAX as usize).then(|| {
        Diagnostic::error(Span::new(0, 0), "file larger than 4 GiB; not parsed")
            .with_hint("split the program; robot controllers do not load files this large")
    })
}

/// The tree of a source [`too_large`] refused: the root and one empty opaque leaf.
pub(crate) fn refused_tree<L: Language>(opaque: L::Kind) -> Tree<L> {
    let mut b = TreeBuilder::<L>::with_capacity(2);
    b.leaf(opaque, 0, 0);
    b.finish(0).tree
}

/// Bytes as a quoted, escaped string: ASCII graphic as is, everything else `\xNN`/`\r`/`\n`.
pub(crate) fn escape(bytes: &[u8]) -> String {
    let mut s = String::with_capacity(bytes.len() + 2);
    s.push('"');
    for &b in bytes {
        match b {
            b'\n' => s.push_str("\\n"),
            b'\r' => s.push_str("\\r"),
            b'\t' => s.push_str("\\t"),
            b'"' => s.push_str("\\\""),
            b'\\' => s.push_str("\\\\"),
            0x20..=0x7E => s.push(b as char),
            _ => s.push_str(&format!("\\x{b:02X}")),
        }
    }
    s.push('"');
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    enum K {
        Root,
        Gap,
        Block,
        Word,
    }

    struct Toy;

    impl Language for Toy {
        type Kind = K;
        const ROOT: K = K::Root;
        const GAP: K = K::Gap;
        fn is_branch(kind: K) -> bool {
            matches!(kind, K::Root | K::Block)
        }
    }

    #[test]
    fn builder_fills_gaps_and_nests_in_pre_order() {
        let src = b"a {b} c";
        let mut b = TreeBuilder::<Toy>::with_capacity(8);
        b.leaf(K::Word, 0, 1);
        let block = b.open(K::Block, 2);
        b.leaf(K::Word, 2, 5);
        b.close(block);
        b.leaf(K::Word, 6, 7);
        let built = b.finish(src.len() as u32);
        assert!(built.round_trip);
        let tree = built.tree;
        assert_eq!(
            tree.dump(src),
            "Root@0..7\n  Word@0..1 \"a\"\n  Gap@1..2 \" \"\n  Block@2..5\n    Word@2..5 \"{b}\"\n  Gap@5..6 \" \"\n  Word@6..7 \"c\"\n"
        );
        assert!(tree.prints_back(src));
        assert_eq!(tree.print(src), src);
        assert!(!tree.prints_back(b"a {b} cd"));
        let mut lost = tree.clone();
        lost.nodes.remove(2);
        assert!(!lost.prints_back(src));
        let mut doubled = tree.clone();
        doubled.nodes.insert(2, tree.nodes[1]);
        assert!(!doubled.prints_back(src));
    }

    /// The leaves of `builder_fills_gaps_and_nests_in_pre_order`, pushed into `b`.
    fn toy_leaves(mut b: TreeBuilder<Toy>, src_len: u32) -> Built<Toy> {
        b.leaf(K::Word, 0, 1);
        let block = b.open(K::Block, 2);
        b.leaf(K::Word, 2, 5);
        b.close(block);
        b.leaf(K::Word, 6, 7);
        b.finish(src_len)
    }

    #[test]
    fn a_verifying_builder_keeps_no_nodes_and_finds_what_prints_back_finds() {
        let src = b"a {b} c";
        let kept = toy_leaves(TreeBuilder::with_capacity(8), 7);
        let verified = toy_leaves(TreeBuilder::verifying(), 7);
        assert!(kept.round_trip && verified.round_trip);
        assert!(verified.tree.nodes.is_empty());
        assert_eq!(kept.tree.nodes.len(), 7);
        assert!(kept.tree.prints_back(src));
        // A source longer than the leaves (the finishing gap covers it) still round-trips; one
        // shorter than them does not.
        assert!(toy_leaves(TreeBuilder::verifying(), 9).round_trip);
        assert!(!toy_leaves(TreeBuilder::verifying(), 6).round_trip);
        // A leaf that starts inside the one before it: bytes printed twice.
        for mut b in [
            TreeBuilder::<Toy>::with_capacity(4),
            TreeBuilder::verifying(),
        ] {
            b.leaf(K::Word, 0, 3);
            b.leaf(K::Word, 2, 5);
            let built = b.finish(5);
            assert!(!built.round_trip);
            if !built.tree.nodes.is_empty() {
                assert!(!built.tree.prints_back(b"abcde"));
            }
        }
        // Node indices advance the same whether or not the nodes are kept.
        let mut kept = TreeBuilder::<Toy>::with_capacity(4);
        let mut verifying = TreeBuilder::<Toy>::verifying();
        for b in [&mut kept, &mut verifying] {
            // Root, gap 0..1, the word, gap 2..3, then the block.
            b.leaf(K::Word, 1, 2);
            assert_eq!(b.open(K::Block, 3), 4);
            assert_eq!(b.len(), 5);
        }
    }

    #[test]
    fn closures_are_sinks() {
        let mut seen = Vec::new();
        {
            let mut sink = |e: u32| seen.push(e);
            let dyn_sink: &mut dyn Sink<u32> = &mut sink;
            dyn_sink.accept(3);
            dyn_sink.accept(4);
        }
        NoSink.accept(5u32);
        assert_eq!(seen, [3, 4]);
    }
}
