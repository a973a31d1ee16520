//! Rigid fit of point pairs (Kabsch/Horn closed form refined by least squares).
//!
//! Owned by the track-model work (issue 4).
