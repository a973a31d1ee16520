//! Program transforms (DESIGN.md §4): `correct`, `zero`, `mirror`, `transfer`, and the cell
//! file that describes robots, tracks and the mirror plane.
//!
//! Owned by issue 5.
