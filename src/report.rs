//! What `inspect` and `check` report about programs: positions, summaries, lints.
