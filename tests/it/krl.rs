//! Integration tests: krl.
