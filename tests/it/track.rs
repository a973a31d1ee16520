//! Integration tests: track.
