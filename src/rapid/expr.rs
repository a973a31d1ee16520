//! Expressions of one statement, in a scratch arena reused statement after statement.
//!
//! Aggregates, calls and arguments are allocated before their children, so their subtree is the
//! index range `id..subtree_end`. Compound and access nodes wrap an operand that was read before
//! it was known to be one, so they come after their first child; nothing relies on their range.

use crate::syntax::{NumLit, Span};

/// No node (end of a sibling list, no child).
pub(crate) const NONE: u32 = u32::MAX;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum ExprKind {
    /// A numeric literal, with a directly attached sign included in the span (`-0.5`).
    Num,
    Str,
    /// `TRUE`, `p10`, `tool0`.
    Ident,
    /// `[a, b, ...]` — children are the elements.
    Aggregate,
    /// `name(args)` — `name` holds the name's span; children are [`ExprKind::Arg`]s.
    Call,
    /// One argument: `\name`, `\name:=value`, `\name?var`, `name:=value` or a plain value.
    /// `name` holds the argument name (if any); the child is the value (if any).
    Arg,
    /// `base{i, j}` or `base.field` — the first child is the base, then the indices.
    Access,
    /// Operands joined by operators or under a unary operator / parentheses.
    Compound,
    /// `<EXP>`, `<ARG>`, ...
    Placeholder,
    /// `%expr%` — the child is the expression naming the routine.
    Late,
    /// The argument list of a procedure call statement; children are [`ExprKind::Arg`]s.
    Args,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct ExprNode {
    pub kind: ExprKind,
    pub start: u32,
    pub end: u32,
    /// The argument or routine name, for [`ExprKind::Arg`] and [`ExprKind::Call`].
    pub name_start: u32,
    pub name_end: u32,
    /// `\name` switch-style argument.
    pub switch: bool,
    pub first: u32,
    pub next: u32,
    pub subtree_end: u32,
    /// For an [`ExprKind::Num`] read by the numeric-aggregate fast path: its literal in
    /// [`Arena::lits`], parsed while the number was scanned ([`NONE`] otherwise).
    pub lit: u32,
}

impl ExprNode {
    pub(crate) fn span(&self) -> Span {
        Span::new(self.start as usize, self.end as usize)
    }

    pub(crate) fn name_span(&self) -> Span {
        Span::new(self.name_start as usize, self.name_end as usize)
    }
}

/// The expression nodes of the statement being read.
#[derive(Clone, Debug, Default)]
pub(crate) struct Arena {
    pub nodes: Vec<ExprNode>,
    /// Literals already parsed by the parser, so that the extractor does not parse the same
    /// bytes again (a robtarget file is mostly numbers).
    lits: Vec<NumLit>,
}

impl Arena {
    pub(crate) fn clear(&mut self) {
        self.nodes.clear();
        self.lits.clear();
    }

    /// Where [`truncate`](Self::truncate) can go back to.
    pub(crate) fn mark(&self) -> (usize, usize) {
        (self.nodes.len(), self.lits.len())
    }

    /// Drops every node (and literal) allocated since `mark`.
    pub(crate) fn truncate(&mut self, (nodes, lits): (usize, usize)) {
        self.nodes.truncate(nodes);
        self.lits.truncate(lits);
    }

    /// Allocates a closed [`ExprKind::Num`] node spanning `start..end` whose literal is `lit`.
    pub(crate) fn num(&mut self, start: u32, end: u32, lit: NumLit) -> u32 {
        let id = self.open(ExprKind::Num, start);
        if let Some(n) = self.nodes.get_mut(id as usize) {
            n.end = end;
            n.lit = self.lits.len() as u32;
        }
        self.lits.push(lit);
        id
    }

    /// The literal the parser read for node `n`, if it did.
    pub(crate) fn lit(&self, n: &ExprNode) -> Option<NumLit> {
        self.lits.get(n.lit as usize).copied()
    }

    /// Whether expression `id` is numbers, strings and aggregates of them only: a value that
    /// reads no name (a literal target).
    pub(crate) fn reads_no_name(&self, id: u32) -> bool {
        let Some(n) = self.get(id) else { return false };
        let subtree = self.nodes.get(id as usize..n.subtree_end as usize);
        subtree.is_some_and(|nodes| {
            nodes
                .iter()
                .all(|n| matches!(n.kind, ExprKind::Num | ExprKind::Str | ExprKind::Aggregate))
        })
    }

    pub(crate) fn get(&self, id: u32) -> Option<&ExprNode> {
        self.nodes.get(id as usize)
    }

    /// Allocates a node whose children will follow it.
    pub(crate) fn open(&mut self, kind: ExprKind, start: u32) -> u32 {
        let id = self.nodes.len() as u32;
        self.nodes.push(ExprNode {
            kind,
            start,
            end: start,
            name_start: start,
            name_end: start,
            switch: false,
            first: NONE,
            next: NONE,
            subtree_end: id + 1,
            lit: NONE,
        });
        id
    }

    /// Closes node `id` at byte `end`: its subtree is everything allocated since.
    pub(crate) fn close(&mut self, id: u32, end: u32) {
        let len = self.nodes.len() as u32;
        if let Some(n) = self.nodes.get_mut(id as usize) {
            n.end = end;
            n.subtree_end = len;
        }
    }

    pub(crate) fn set_mut(&mut self, id: u32) -> Option<&mut ExprNode> {
        self.nodes.get_mut(id as usize)
    }

    /// Links `child` after `last` (or as `parent`'s first child when `last` is [`NONE`]).
    pub(crate) fn link(&mut self, parent: u32, last: u32, child: u32) {
        if last == NONE {
            if let Some(p) = self.nodes.get_mut(parent as usize) {
                p.first = child;
            }
        } else if let Some(l) = self.nodes.get_mut(last as usize) {
            l.next = child;
        }
    }

    /// The children of `id`, in order.
    pub(crate) fn children(&self, id: u32) -> Children<'_> {
        Children {
            arena: self,
            next: self.get(id).map_or(NONE, |n| n.first),
        }
    }

    /// The value of an [`ExprKind::Arg`] (its child), or the node itself otherwise.
    pub(crate) fn arg_value(&self, id: u32) -> Option<u32> {
        let n = self.get(id)?;
        if n.kind == ExprKind::Arg {
            (n.first != NONE).then_some(n.first)
        } else {
            Some(id)
        }
    }
}

pub(crate) struct Children<'a> {
    arena: &'a Arena,
    next: u32,
}

impl Iterator for Children<'_> {
    type Item = u32;

    fn next(&mut self) -> Option<u32> {
        if self.next == NONE {
            return None;
        }
        let id = self.next;
        self.next = self.arena.get(id).map_or(NONE, |n| n.next);
        Some(id)
    }
}
