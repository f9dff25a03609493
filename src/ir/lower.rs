//! Lowering from the scene AST to SSA IR.
