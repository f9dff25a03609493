//! Reference evaluators over the IR in plain Rust: the oracle the JIT is
//! tested against.
