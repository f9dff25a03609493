//! Tokens of the scene language, produced by a logos lexer and handed to
//! the LALRPOP parser as `(start, token, end)` byte-offset triples.

use super::diag::Diag;
use logos::Logos;

/// One token. Numbers keep their text so that a malformed literal can be
/// reported with its span by the parser.
#[derive(Logos, Clone, Copy, Debug, PartialEq)]
#[logos(skip r"[ \t\r\n\f]+")]
#[logos(skip(r"//[^\n]*", allow_greedy = true))]
pub enum Tok<'a> {
    /// `let`
    #[token("let")]
    Let,
    /// `fn`
    #[token("fn")]
    Fn,
    /// `object`
    #[token("object")]
    Object,
    /// `camera`
    #[token("camera")]
    Camera,
    /// `light`
    #[token("light")]
    Light,
    /// `render`
    #[token("render")]
    Render,
    /// `bounds`
    #[token("bounds")]
    Bounds,
    /// `true`
    #[token("true")]
    True,
    /// `false`
    #[token("false")]
    False,
    /// `import`
    #[token("import")]
    Import,
    /// A string literal, quotes included: `"lib/shapes.ib"`. There are no
    /// escapes, and a string ends on its line, so a missing closing quote
    /// is reported where the string starts instead of swallowing the file.
    #[regex(r#""[^"\n]*""#)]
    Str(&'a str),
    /// A string without its closing quote on the same line.
    #[regex(r#""[^"\n]*"#)]
    BadStr(&'a str),
    /// A name: a letter or `_`, then letters, digits and `_`.
    #[regex("[A-Za-z_][A-Za-z0-9_]*")]
    Ident(&'a str),
    /// A well-formed number literal: `1`, `2.5`, `.5`, `1e-3`.
    #[regex(r"([0-9]+(\.[0-9]*)?|\.[0-9]+)([eE][+-]?[0-9]+)?", priority = 10)]
    Num(&'a str),
    /// Something that starts like a number but is not one (`1.2.3`, `1e`,
    /// `2x`); the longest such run is reported as one bad literal.
    #[regex(r"[0-9][0-9A-Za-z_.]*", priority = 1)]
    BadNum(&'a str),
    /// `(`
    #[token("(")]
    LParen,
    /// `)`
    #[token(")")]
    RParen,
    /// `{`
    #[token("{")]
    LBrace,
    /// `}`
    #[token("}")]
    RBrace,
    /// `,`
    #[token(",")]
    Comma,
    /// `;`
    #[token(";")]
    Semi,
    /// `=`
    #[token("=")]
    Eq,
    /// `+`
    #[token("+")]
    Plus,
    /// `-`
    #[token("-")]
    Minus,
    /// `*`
    #[token("*")]
    Star,
    /// `/`
    #[token("/")]
    Slash,
    /// `^`
    #[token("^")]
    Caret,
    /// `..`
    #[token("..")]
    DotDot,
}

/// The token stream the parser consumes; lexing errors end the parse with
/// a diagnostic.
pub struct Lexer<'a> {
    inner: logos::SpannedIter<'a, Tok<'a>>,
    src: usize,
}

impl<'a> Lexer<'a> {
    /// Lexes `text`, which is source number `src` (for diagnostics).
    pub fn new(text: &'a str, src: usize) -> Lexer<'a> {
        Lexer {
            inner: Tok::lexer(text).spanned(),
            src,
        }
    }
}

impl<'a> Iterator for Lexer<'a> {
    type Item = Result<(usize, Tok<'a>, usize), Diag>;

    fn next(&mut self) -> Option<Self::Item> {
        let (tok, span) = self.inner.next()?;
        Some(match tok {
            Ok(Tok::BadNum(text)) => {
                Err(
                    Diag::new(self.src, span, format!("bad number literal `{text}`"))
                        .with_help(bad_number_help(text)),
                )
            }
            Ok(Tok::BadStr(_)) => Err(Diag::new(
                self.src,
                span,
                "unterminated string: no closing `\"` on this line".into(),
            )
            .with_help("a path is written on one line, e.g. `import \"lib/shapes.ib\";`")),
            Ok(tok) => Ok((span.start, tok, span.end)),
            Err(()) => {
                let text = self.inner.slice();
                let shown = text.chars().next().unwrap_or(' ');
                let d = Diag::new(
                    self.src,
                    span,
                    format!("unexpected character `{}`", shown.escape_debug()),
                );
                Err(match shown {
                    '²' => d.with_help("write powers with `^`, e.g. `x^2`"),
                    '³' => d.with_help("write powers with `^`, e.g. `x^3`"),
                    '·' | '×' => d.with_help("write products with `*`"),
                    '−' => d.with_help("this is a Unicode minus sign; use `-`"),
                    _ => d,
                })
            }
        })
    }
}

/// A hint for the most common malformed numbers.
fn bad_number_help(text: &str) -> String {
    let digits_then_letter = text
        .find(|c: char| c.is_ascii_alphabetic() && c != 'e' && c != 'E')
        .is_some();
    if digits_then_letter {
        "multiplication must be written out, e.g. `2*x`".into()
    } else {
        "a number is digits, an optional `.` and fraction, and an optional exponent like `e-3`"
            .into()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kinds(text: &str) -> Vec<Tok<'_>> {
        Lexer::new(text, 0)
            .map(|t| {
                t.map(|(_, k, _)| k)
                    .unwrap_or_else(|d| panic!("{}", d.message))
            })
            .collect()
    }

    #[test]
    fn numbers_names_keywords_and_comments() {
        assert_eq!(
            kinds("let r2 = .5e1 // c\n..x"),
            vec![
                Tok::Let,
                Tok::Ident("r2"),
                Tok::Eq,
                Tok::Num(".5e1"),
                Tok::DotDot,
                Tok::Ident("x")
            ]
        );
        assert_eq!(
            kinds("1 2. 3.25 4e-3"),
            vec![
                Tok::Num("1"),
                Tok::Num("2."),
                Tok::Num("3.25"),
                Tok::Num("4e-3")
            ]
        );
        assert_eq!(kinds("lettuce"), vec![Tok::Ident("lettuce")]);
        assert_eq!(
            kinds("import \"a b/c.ib\";"),
            vec![Tok::Import, Tok::Str("\"a b/c.ib\""), Tok::Semi]
        );
    }

    #[test]
    fn unterminated_string_is_an_error_on_its_line() {
        let e = Lexer::new("import \"lib.ib;\nlet a = 1;", 0)
            .nth(1)
            .unwrap()
            .unwrap_err();
        assert_eq!(e.span, 7..15);
        assert!(
            e.message.starts_with("unterminated string"),
            "{}",
            e.message
        );
    }

    #[test]
    fn bad_numbers_and_characters_are_errors_with_spans() {
        let e = Lexer::new("x + 1.2.3", 0).nth(2).unwrap().unwrap_err();
        assert_eq!(
            (e.span, e.message.as_str()),
            (4..9, "bad number literal `1.2.3`")
        );
        let e = Lexer::new("x²", 0).nth(1).unwrap().unwrap_err();
        assert_eq!(e.span, 1..3);
        assert_eq!(e.help.as_deref(), Some("write powers with `^`, e.g. `x^2`"));
    }
}
