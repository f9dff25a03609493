//! Cranelift JIT: native point, interval and gradient evaluators.
