//! Glue between the generated LALRPOP parser and the AST: node builders
//! called from grammar actions (they enforce [`MAX_DEPTH`] and flatten
//! `+ -` and `* /` chains), and the conversion of parse errors into
//! diagnostics.

use super::ast::{AddOp, Expr, ExprKind, Ident, Item, MAX_DEPTH, MulOp, Span};
use super::diag::Diag;
use super::lexer::{Lexer, Tok};
use lalrpop_util::ParseError;

lalrpop_util::lalrpop_mod!(
    #[allow(clippy::all, clippy::pedantic, unused_parens, missing_docs)]
    grammar,
    "/scene.rs"
);

type PResult<'a> = Result<Expr, ParseError<usize, Tok<'a>, Diag>>;

/// Parses a whole scene file (source number `src`).
pub fn parse_file(text: &str, src: usize) -> Result<Vec<Item>, Diag> {
    grammar::FileParser::new()
        .parse(src, Lexer::new(text, src))
        .map_err(|e| convert(e, src, text))
}

/// Parses a single expression (source number `src`).
pub fn parse_expr(text: &str, src: usize) -> Result<Expr, Diag> {
    grammar::ExprParser::new()
        .parse(src, Lexer::new(text, src))
        .map_err(|e| convert(e, src, text))
}

fn node<'a>(src: usize, kind: ExprKind, span: Span, depth: u32) -> PResult<'a> {
    if depth > MAX_DEPTH {
        return Err(ParseError::User {
            error: Diag::new(
                src,
                span.0..span.1,
                format!("expression nested too deeply (more than {MAX_DEPTH} levels)"),
            )
            .with_help("split it into `let` or `fn` definitions"),
        });
    }
    Ok(Expr { kind, span, depth })
}

/// `a ± b`, appending to `a` when it already is a sum.
pub fn sum<'a>(src: usize, a: Expr, op: AddOp, b: Expr, span: Span) -> PResult<'a> {
    let depth = a.depth.max(b.depth + 1);
    match a.kind {
        ExprKind::Sum(mut terms) => {
            terms.push((op, b));
            node(src, ExprKind::Sum(terms), span, depth)
        }
        _ => {
            let depth = a.depth.max(b.depth) + 1;
            node(
                src,
                ExprKind::Sum(vec![(AddOp::Add, a), (op, b)]),
                span,
                depth,
            )
        }
    }
}

/// `a */ b`, appending to `a` when it already is a product.
pub fn product<'a>(src: usize, a: Expr, op: MulOp, b: Expr, span: Span) -> PResult<'a> {
    let depth = a.depth.max(b.depth + 1);
    match a.kind {
        ExprKind::Product(mut terms) => {
            terms.push((op, b));
            node(src, ExprKind::Product(terms), span, depth)
        }
        _ => {
            let depth = a.depth.max(b.depth) + 1;
            node(
                src,
                ExprKind::Product(vec![(MulOp::Mul, a), (op, b)]),
                span,
                depth,
            )
        }
    }
}

/// `-e`.
pub fn neg<'a>(src: usize, e: Expr, span: Span) -> PResult<'a> {
    let depth = e.depth + 1;
    node(src, ExprKind::Neg(Box::new(e)), span, depth)
}

/// `a ^ b`.
pub fn pow<'a>(src: usize, a: Expr, b: Expr, span: Span) -> PResult<'a> {
    let depth = a.depth.max(b.depth) + 1;
    node(src, ExprKind::Pow(Box::new(a), Box::new(b)), span, depth)
}

/// A number literal; rejects literals that overflow to infinity.
pub fn number<'a>(src: usize, text: &str, span: Span) -> PResult<'a> {
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() => node(src, ExprKind::Num(v), span, 1),
        _ => Err(ParseError::User {
            error: Diag::new(
                src,
                span.0..span.1,
                format!("bad number literal `{text}`: out of range"),
            )
            .with_help("numbers must be finite 64-bit floats (at most about 1.8e308)"),
        }),
    }
}

/// A bare name.
pub fn name(n: Ident) -> Expr {
    Expr {
        kind: ExprKind::Name(n.name),
        span: n.span,
        depth: 1,
    }
}

/// `name(args)`; `end` is the offset after the closing parenthesis.
pub fn call<'a>(src: usize, n: Ident, args: Vec<Expr>, end: usize) -> PResult<'a> {
    let depth = args.iter().map(|a| a.depth).max().unwrap_or(0) + 1;
    node(
        src,
        ExprKind::Call {
            name: n.name,
            name_span: n.span,
            args,
        },
        (n.span.0, end),
        depth,
    )
}

/// How a grammar terminal is shown in "expected …" hints.
fn show_expected(t: &str) -> String {
    match t {
        "\"name\"" => "a name".into(),
        "\"number\"" => "a number".into(),
        "\"string\"" => "a quoted path".into(),
        other => format!("`{}`", other.trim_matches('"')),
    }
}

fn expected_help(expected: &[String]) -> Option<String> {
    if expected.is_empty() {
        return None;
    }
    let shown: Vec<String> = expected.iter().map(|t| show_expected(t)).collect();
    Some(if shown.len() == 1 {
        format!("expected {}", shown[0])
    } else {
        format!("expected one of {}", shown.join(", "))
    })
}

/// How a token is named in "unexpected …" messages.
fn describe(tok: &Tok<'_>, text: &str) -> String {
    match tok {
        Tok::Ident(n) => format!("name `{n}`"),
        Tok::Num(n) => format!("number `{n}`"),
        Tok::Str(s) => format!("string {s}"),
        _ => format!("`{text}`"),
    }
}

fn convert(e: ParseError<usize, Tok<'_>, Diag>, src: usize, text: &str) -> Diag {
    match e {
        ParseError::User { error } => error,
        ParseError::InvalidToken { location } => {
            Diag::new(src, location..location, "invalid token".to_string())
        }
        ParseError::UnrecognizedEof { location, expected } => {
            let d = Diag::new(src, location..location, "unexpected end of input".into());
            match expected_help(&expected) {
                Some(h) => d.with_help(h),
                None => d,
            }
        }
        ParseError::UnrecognizedToken {
            token: (l, tok, r),
            expected,
        } => {
            let shown = describe(&tok, text.get(l..r).unwrap_or(""));
            let d = Diag::new(src, l..r, format!("unexpected {shown}"));
            let after_block = text.get(..l).and_then(|t| t.trim_end().chars().last()) == Some('}');
            if tok == Tok::Semi && after_block {
                return d.with_help("a block `{ … }` is not followed by `;`");
            }
            match expected_help(&expected) {
                Some(h) if expected.iter().any(|t| t == "\";\"") => {
                    d.with_help(format!("{h}; is a `;` missing before this?"))
                }
                Some(h) => d.with_help(h),
                None => d,
            }
        }
        ParseError::ExtraToken { token: (l, tok, r) } => {
            let shown = describe(&tok, text.get(l..r).unwrap_or(""));
            Diag::new(src, l..r, format!("unexpected {shown} after the end"))
        }
    }
}
