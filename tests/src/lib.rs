//! End-to-end tests across the foxhunt crates live in `tests/`.
