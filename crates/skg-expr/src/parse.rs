//! The expression parser (grammar in the module docs of [`crate`]).

use super::{ExprId, Func, Graph, Symbol};

/// What went wrong in a [`ParseError`].
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub enum ParseErrorKind {
    /// The expression is empty or all whitespace.
    EmptyExpression,
    /// A character that is not part of the grammar.
    UnexpectedCharacter,
    /// A token where an operand or operator of another kind was required.
    UnexpectedToken,
    /// The expression ended where more was required.
    UnexpectedEnd,
    /// A `(` without its `)`.
    MissingCloseParen,
    /// A `)` without its `(`.
    UnmatchedCloseParen,
    /// A malformed or out-of-range number.
    InvalidNumber,
    /// A call of a name that is not a function.
    UnknownFunction,
    /// A function called with the wrong number of arguments.
    WrongArgumentCount,
    /// A name that is neither built in nor known to the caller's resolver.
    UnknownSymbol,
    /// Input left over after a complete expression.
    TrailingInput,
    /// Parentheses, signs or powers nested too deeply.
    TooDeep,
}

/// An error in an expression string, with the character position where it was found.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{message} at position {position} in `{}`{}", self.excerpt().0, .hint.as_ref().map(|h| format!("; {h}")).unwrap_or_default())]
pub struct ParseError {
    /// The whole expression string.
    pub source_text: String,
    /// Where the error is: a 0-based offset in characters (not bytes) into `source_text`.
    pub position: usize,
    /// What is wrong, e.g. "unknown symbol `q`".
    pub message: String,
    /// The kind of error.
    pub kind: ParseErrorKind,
    /// Extra advice added by the caller (e.g. the list of valid names), shown after the
    /// message.
    pub hint: Option<String>,
}

impl ParseError {
    fn new(src: &str, position: usize, kind: ParseErrorKind, message: impl Into<String>) -> Self {
        ParseError { source_text: src.to_string(), position, message: message.into(), kind, hint: None }
    }

    /// Attach a hint (for example "valid names are x, y, x_dot, y_dot"), shown after the
    /// message.
    pub fn with_hint(mut self, hint: impl Into<String>) -> Self {
        self.hint = Some(hint.into());
        self
    }

    /// The source and, below it, a `^` under the error position:
    ///
    /// ```text
    /// x + * y
    ///     ^
    /// ```
    ///
    /// A long source is shown as the 60 characters on either side of the position, with
    /// `…` where it is cut (a message never echoes a whole generated expression).
    pub fn caret_line(&self) -> String {
        let (shown, at) = self.excerpt();
        let pad: String = shown.chars().take(at).map(|c| if c == '\t' { '\t' } else { ' ' }).collect();
        let extra = at.saturating_sub(shown.chars().count());
        format!("{shown}\n{pad}{}^", " ".repeat(extra))
    }

    /// The part of the source that messages show (all of it unless it is long: see
    /// [`ParseError::caret_line`]) and the position in it, in characters.
    fn excerpt(&self) -> (String, usize) {
        let count = self.source_text.chars().count();
        let start = self.position.saturating_sub(EXCERPT_CHARS).min(count);
        let end = self.position.saturating_add(EXCERPT_CHARS).min(count);
        let body: String = self.source_text.chars().skip(start).take(end - start).collect();
        let head = if start > 0 { "…" } else { "" };
        let tail = if end < count { "…" } else { "" };
        (format!("{head}{body}{tail}"), self.position - start + head.chars().count())
    }
}

/// Characters of the source shown on either side of an error's position.
const EXCERPT_CHARS: usize = 60;

/// Deepest nesting of parentheses, signs and exponents accepted, so that hostile input
/// cannot overflow the stack.
const MAX_DEPTH: usize = 200;

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Num(f64),
    Name(String),
    Plus,
    Minus,
    Star,
    Slash,
    Caret,
    LParen,
    RParen,
    Comma,
    End,
    /// A lexical error, reported when the parser reaches it.
    Bad(ParseErrorKind, String),
}

fn describe(t: &Tok) -> String {
    match t {
        Tok::Num(_) => "number".into(),
        Tok::Name(n) => format!("`{n}`"),
        Tok::Plus => "`+`".into(),
        Tok::Minus => "`-`".into(),
        Tok::Star => "`*`".into(),
        Tok::Slash => "`/`".into(),
        Tok::Caret => "`^`".into(),
        Tok::LParen => "`(`".into(),
        Tok::RParen => "`)`".into(),
        Tok::Comma => "`,`".into(),
        Tok::End => "end of expression".into(),
        Tok::Bad(_, m) => m.clone(),
    }
}

/// Split `chars` into tokens with their character positions; the last is always `End`.
fn lex(chars: &[char]) -> Vec<(Tok, usize)> {
    let mut toks = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if c.is_whitespace() {
            i += 1;
            continue;
        }
        let start = i;
        let tok = match c {
            '+' => Tok::Plus,
            '-' => Tok::Minus,
            // `**` is a power as `^` is (Python's and SymPy's spelling).
            '*' if chars.get(i + 1) == Some(&'*') => {
                toks.push((Tok::Caret, start));
                i += 2;
                continue;
            }
            '*' => Tok::Star,
            '/' => Tok::Slash,
            '^' => Tok::Caret,
            '(' => Tok::LParen,
            ')' => Tok::RParen,
            ',' => Tok::Comma,
            '0'..='9' | '.' => {
                let (tok, end) = lex_number(chars, i);
                i = end;
                toks.push((tok, start));
                continue;
            }
            c if c.is_ascii_alphabetic() || c == '_' => {
                while i < chars.len() && (chars[i].is_ascii_alphanumeric() || chars[i] == '_') {
                    i += 1;
                }
                toks.push((Tok::Name(chars[start..i].iter().collect()), start));
                continue;
            }
            c => Tok::Bad(ParseErrorKind::UnexpectedCharacter, format!("unexpected character `{}`", c.escape_debug())),
        };
        toks.push((tok, start));
        i += 1;
    }
    toks.push((Tok::End, chars.len()));
    toks
}

/// Lex a number starting at `i`; returns the token and the index after it.
fn lex_number(chars: &[char], mut i: usize) -> (Tok, usize) {
    let start = i;
    let digits = |i: &mut usize| {
        let s = *i;
        while *i < chars.len() && chars[*i].is_ascii_digit() {
            *i += 1;
        }
        *i - s
    };
    let mut mantissa = digits(&mut i);
    if i < chars.len() && chars[i] == '.' {
        i += 1;
        mantissa += digits(&mut i);
    }
    if mantissa == 0 {
        return (Tok::Bad(ParseErrorKind::InvalidNumber, "invalid number `.` (no digits)".into()), i);
    }
    if i < chars.len() && (chars[i] == 'e' || chars[i] == 'E') {
        let mut j = i + 1;
        if j < chars.len() && (chars[j] == '+' || chars[j] == '-') {
            j += 1;
        }
        if digits(&mut j) == 0 {
            let text: String = chars[start..i + 1].iter().collect();
            return (Tok::Bad(ParseErrorKind::InvalidNumber, format!("invalid number `{text}`: the exponent has no digits")), j);
        }
        i = j;
    }
    let text: String = chars[start..i].iter().collect();
    match text.parse::<f64>() {
        Ok(x) if x.is_finite() => (Tok::Num(x), i),
        _ => (Tok::Bad(ParseErrorKind::InvalidNumber, format!("number `{text}` is out of range")), i),
    }
}

struct Parser<'a, 'r> {
    src: &'a str,
    toks: Vec<(Tok, usize)>,
    at: usize,
    depth: usize,
    graph: &'a mut Graph,
    resolve: &'a mut (dyn FnMut(&str) -> Option<Symbol> + 'r),
}

type PResult = Result<ExprId, ParseError>;

impl Parser<'_, '_> {
    fn peek(&self) -> &Tok {
        &self.toks[self.at].0
    }

    fn pos(&self) -> usize {
        self.toks[self.at].1
    }

    fn bump(&mut self) {
        if self.at + 1 < self.toks.len() {
            self.at += 1;
        }
    }

    fn err(&self, pos: usize, kind: ParseErrorKind, msg: impl Into<String>) -> ParseError {
        ParseError::new(self.src, pos, kind, msg)
    }

    /// Error for the current token when an operand was expected.
    fn unexpected_operand(&self) -> ParseError {
        let pos = self.pos();
        match self.peek() {
            Tok::End => self.err(pos, ParseErrorKind::UnexpectedEnd, "unexpected end of expression (expected a number, a name or `(`)"),
            Tok::Bad(kind, msg) => self.err(pos, *kind, msg.clone()),
            t => self.err(pos, ParseErrorKind::UnexpectedToken, format!("unexpected {} (expected a number, a name or `(`)", describe(t))),
        }
    }

    fn expr(&mut self) -> PResult {
        let mut lhs = self.term()?;
        loop {
            match self.peek() {
                Tok::Plus => {
                    self.bump();
                    let rhs = self.term()?;
                    lhs = self.graph.add(lhs, rhs);
                }
                Tok::Minus => {
                    self.bump();
                    let rhs = self.term()?;
                    lhs = self.graph.sub(lhs, rhs);
                }
                _ => return Ok(lhs),
            }
        }
    }

    fn term(&mut self) -> PResult {
        let mut lhs = self.unary()?;
        loop {
            match self.peek() {
                Tok::Star => {
                    self.bump();
                    let rhs = self.unary()?;
                    lhs = self.graph.mul(lhs, rhs);
                }
                Tok::Slash => {
                    self.bump();
                    let rhs = self.unary()?;
                    lhs = self.graph.div(lhs, rhs);
                }
                _ => return Ok(lhs),
            }
        }
    }

    fn unary(&mut self) -> PResult {
        if self.depth >= MAX_DEPTH {
            return Err(self.err(self.pos(), ParseErrorKind::TooDeep, format!("expression nested more than {MAX_DEPTH} levels deep")));
        }
        self.depth += 1;
        let r = match self.peek() {
            Tok::Minus => {
                self.bump();
                self.unary().map(|a| self.graph.neg(a))
            }
            Tok::Plus => {
                self.bump();
                self.unary()
            }
            _ => self.power(),
        };
        self.depth -= 1;
        r
    }

    fn power(&mut self) -> PResult {
        let base = self.primary()?;
        if *self.peek() == Tok::Caret {
            self.bump();
            let exponent = self.unary()?;
            return Ok(self.graph.pow(base, exponent));
        }
        Ok(base)
    }

    fn primary(&mut self) -> PResult {
        let pos = self.pos();
        match self.peek().clone() {
            Tok::Num(x) => {
                self.bump();
                Ok(self.graph.constant(x))
            }
            Tok::LParen => {
                self.bump();
                let e = self.expr()?;
                self.close_paren(pos)?;
                Ok(e)
            }
            Tok::Name(name) => {
                self.bump();
                if *self.peek() == Tok::LParen {
                    self.call(&name, pos)
                } else {
                    self.symbol(&name, pos)
                }
            }
            _ => Err(self.unexpected_operand()),
        }
    }

    fn close_paren(&mut self, open: usize) -> Result<(), ParseError> {
        match self.peek() {
            Tok::RParen => {
                self.bump();
                Ok(())
            }
            Tok::Bad(kind, msg) => Err(self.err(self.pos(), *kind, msg.clone())),
            t => Err(self.err(
                self.pos(),
                ParseErrorKind::MissingCloseParen,
                format!("missing `)` to close the `(` at position {open} (found {})", describe(t)),
            )),
        }
    }

    fn call(&mut self, name: &str, pos: usize) -> PResult {
        let arity = match (name, Func::from_name(name)) {
            (_, Some(_)) => 1,
            ("atan2", None) => 2,
            _ => {
                let known: Vec<&str> = Func::ALL.iter().map(|f| f.name()).chain(["atan2"]).collect();
                return Err(self.err(
                    pos,
                    ParseErrorKind::UnknownFunction,
                    format!("unknown function `{name}` (known: {})", known.join(", ")),
                ));
            }
        };
        let open = self.pos();
        self.bump(); // `(`
        let mut args = Vec::new();
        if *self.peek() != Tok::RParen {
            loop {
                args.push(self.expr()?);
                if *self.peek() == Tok::Comma {
                    self.bump();
                } else {
                    break;
                }
            }
        }
        self.close_paren(open)?;
        if args.len() != arity {
            let plural = if arity == 1 { "" } else { "s" };
            return Err(self.err(
                pos,
                ParseErrorKind::WrongArgumentCount,
                format!("`{name}` takes {arity} argument{plural}, got {}", args.len()),
            ));
        }
        Ok(match Func::from_name(name) {
            Some(f) => self.graph.func(f, args[0]),
            None => self.graph.atan2(args[0], args[1]),
        })
    }

    fn symbol(&mut self, name: &str, pos: usize) -> PResult {
        if name == "pi" {
            return Ok(self.graph.constant(std::f64::consts::PI));
        }
        match (self.resolve)(name) {
            Some(Symbol::Const(c)) => Ok(self.graph.constant(c)),
            Some(Symbol::Expr(e)) if e.index() < self.graph.len() => Ok(e),
            Some(Symbol::Expr(e)) => Err(self.err(
                pos,
                ParseErrorKind::UnknownSymbol,
                format!("symbol `{name}` resolves to expression {}, which this graph does not hold", e.index()),
            )),
            Some(Symbol::Var(i)) => match u32::try_from(i) {
                Ok(_) => Ok(self.graph.var(i)),
                Err(_) => Err(self.err(
                    pos,
                    ParseErrorKind::UnknownSymbol,
                    format!("symbol `{name}` resolves to variable index {i}, which is too large"),
                )),
            },
            None if Func::from_name(name).is_some() || name == "atan2" => Err(self.err(
                pos,
                ParseErrorKind::UnknownSymbol,
                format!("function `{name}` must be called with parentheses, as in `{name}(x)`"),
            )),
            None => Err(self.err(pos, ParseErrorKind::UnknownSymbol, format!("unknown symbol `{name}`"))),
        }
    }
}

impl Graph {
    /// Parse the expression `src` into this graph (grammar in the [module docs](crate)).
    ///
    /// `pi` is built in; every other name that is not called as a function is passed to
    /// `resolve`, which says whether it is a variable or a named constant, or `None` if it
    /// is unknown (a [`ParseError`] of kind [`ParseErrorKind::UnknownSymbol`] at the
    /// name's position; the caller can add a list of valid names with
    /// [`ParseError::with_hint`]). Never panics, whatever `src` holds. On error the graph
    /// may keep nodes built before the error was found; they do no harm.
    pub fn parse(&mut self, src: &str, resolve: &mut dyn FnMut(&str) -> Option<Symbol>) -> Result<ExprId, ParseError> {
        let chars: Vec<char> = src.chars().collect();
        let toks = lex(&chars);
        if toks.len() == 1 {
            return Err(ParseError::new(src, 0, ParseErrorKind::EmptyExpression, "empty expression"));
        }
        let mut p = Parser { src, toks, at: 0, depth: 0, graph: self, resolve };
        let e = p.expr()?;
        let pos = p.pos();
        match p.peek() {
            Tok::End => Ok(e),
            Tok::RParen => Err(p.err(pos, ParseErrorKind::UnmatchedCloseParen, "unmatched `)`")),
            Tok::Bad(kind, msg) => Err(p.err(pos, *kind, msg.clone())),
            t => Err(p.err(
                pos,
                ParseErrorKind::TrailingInput,
                format!("unexpected {} after a complete expression (missing operator?)", describe(t)),
            )),
        }
    }
}
