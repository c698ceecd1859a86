//! Cross-stage integration tests (one test binary, as in ripgrep).
