//! The guaranteed beam tracer.
