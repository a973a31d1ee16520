//! Integration tests: rapid.
