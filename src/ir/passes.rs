//! Simplification passes, each a function from IR to IR.
