//! The syntax tree built by the parser.
//!
//! Chains of `+ -` and `* /` are stored flat (one node with many terms), and
//! every node records its nesting depth, which the parser caps at
//! [`MAX_DEPTH`]; so no tree is ever deep enough to overflow the stack when
//! it is lowered or dropped, whatever the input.

/// A byte range in one source text.
pub type Span = (usize, usize);

/// The deepest expression tree the parser builds.
pub const MAX_DEPTH: u32 = 512;

/// An expression with its span and nesting depth.
#[derive(Clone, Debug)]
pub struct Expr {
    /// What kind of expression.
    pub kind: ExprKind,
    /// Where it is in the source.
    pub span: Span,
    /// 1 for a leaf, 1 + the deepest child otherwise.
    pub depth: u32,
}

/// `+` or `-` in a sum.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum AddOp {
    /// `+`
    Add,
    /// `-`
    Sub,
}

/// `*` or `/` in a product.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum MulOp {
    /// `*`
    Mul,
    /// `/`
    Div,
}

/// The expression forms.
#[derive(Clone, Debug)]
pub enum ExprKind {
    /// A number literal.
    Num(f64),
    /// A name: a coordinate, a `let`, or a parameter.
    Name(String),
    /// `name(args)`.
    Call {
        /// The function name.
        name: String,
        /// Where the name is.
        name_span: Span,
        /// The arguments, unevaluated.
        args: Vec<Expr>,
    },
    /// `-e`.
    Neg(Box<Expr>),
    /// `base ^ exponent`.
    Pow(Box<Expr>, Box<Expr>),
    /// `t0 ± t1 ± t2 …`, evaluated left to right; the first op is `Add`.
    Sum(Vec<(AddOp, Expr)>),
    /// `f0 */ f1 */ f2 …`, evaluated left to right; the first op is `Mul`.
    Product(Vec<(MulOp, Expr)>),
}

/// A name with its span.
#[derive(Clone, Debug)]
pub struct Ident {
    /// The text.
    pub name: String,
    /// Where it is.
    pub span: Span,
}

/// The right-hand side of a block property.
#[derive(Clone, Debug)]
pub enum PropValue {
    /// A single expression.
    Expr(Expr),
    /// `(a, b, …)` with at least two elements (or one and a trailing comma).
    Tuple(Vec<Expr>, Span),
    /// `true` or `false`.
    Bool(bool, Span),
}

impl PropValue {
    /// Where the value is.
    pub fn span(&self) -> Span {
        match self {
            PropValue::Expr(e) => e.span,
            PropValue::Tuple(_, s) | PropValue::Bool(_, s) => *s,
        }
    }
}

/// `name = value;` inside a block.
#[derive(Clone, Debug)]
pub struct Prop {
    /// The property name.
    pub name: Ident,
    /// Its value.
    pub value: PropValue,
}

/// A top-level item.
#[derive(Clone, Debug)]
pub enum Item {
    /// `let name = body;`
    Let {
        /// The name.
        name: Ident,
        /// The value.
        body: Expr,
    },
    /// `fn name(params) = body;`
    Fn {
        /// The name.
        name: Ident,
        /// The parameters.
        params: Vec<Ident>,
        /// The body.
        body: Expr,
    },
    /// `object name = body;` or `object name = body { props }`.
    Object {
        /// The name.
        name: Ident,
        /// The surface function.
        body: Expr,
        /// Material properties.
        props: Vec<Prop>,
    },
    /// `camera { … }`, `light { … }` or `render { … }`.
    Block {
        /// The keyword, as written.
        keyword: Ident,
        /// The properties.
        props: Vec<Prop>,
    },
    /// `import "path";`: the definitions of another file.
    Import {
        /// The path as written, without quotes (relative paths are taken
        /// from the importing file's folder).
        path: String,
        /// Where the statement is, `import` to the closing quote.
        span: Span,
        /// Where the quoted path is.
        path_span: Span,
    },
    /// `bounds = (…) .. (…);`
    Bounds {
        /// The keyword's span.
        span: Span,
        /// The minimum corner.
        min: (Vec<Expr>, Span),
        /// The maximum corner.
        max: (Vec<Expr>, Span),
    },
}
