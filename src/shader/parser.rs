//! Syntax tree and recursive-descent parser (grammar in `docs/shading-language.md`).

use super::lexer::{lex, Pos, Tok, Token};
use super::ShaderError;
use crate::limits;

/// Value types.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Type {
    /// A scalar.
    Float,
    /// RGB.
    Color,
    /// A position.
    Point,
    /// A direction.
    Vector,
}

impl Type {
    /// From a type keyword.
    pub fn from_name(s: &str) -> Option<Type> {
        match s {
            "float" => Some(Type::Float),
            "color" => Some(Type::Color),
            "point" => Some(Type::Point),
            "vector" => Some(Type::Vector),
            _ => None,
        }
    }

    /// The keyword.
    pub fn name(self) -> &'static str {
        match self {
            Type::Float => "float",
            Type::Color => "color",
            Type::Point => "point",
            Type::Vector => "vector",
        }
    }
}

/// Binary operators.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BinOp {
    /// `+`
    Add,
    /// `-`
    Sub,
    /// `*`
    Mul,
    /// `/`
    Div,
    /// `<`
    Lt,
    /// `<=`
    Le,
    /// `>`
    Gt,
    /// `>=`
    Ge,
    /// `==`
    Eq,
    /// `!=`
    Ne,
    /// `&&`
    And,
    /// `||`
    Or,
}

/// An expression.
#[derive(Clone, Debug, PartialEq)]
pub struct Expr {
    /// What it is.
    pub kind: ExprKind,
    /// Where it starts.
    pub pos: Pos,
}

/// Expression kinds.
#[derive(Clone, Debug, PartialEq)]
pub enum ExprKind {
    /// Literal.
    Num(f64),
    /// Variable, parameter or global.
    Var(String),
    /// Builtin, user function or constructor call.
    Call(String, Vec<Expr>),
    /// `-e`
    Neg(Box<Expr>),
    /// `!e`
    Not(Box<Expr>),
    /// `a op b`
    Binary(BinOp, Box<Expr>, Box<Expr>),
    /// `c ? a : b`
    Ternary(Box<Expr>, Box<Expr>, Box<Expr>),
    /// `e.x`
    Member(Box<Expr>, String),
}

/// A statement.
#[derive(Clone, Debug, PartialEq)]
pub struct Stmt {
    /// What it is.
    pub kind: StmtKind,
    /// Where it starts.
    pub pos: Pos,
}

/// Statement kinds.
#[derive(Clone, Debug, PartialEq)]
pub enum StmtKind {
    /// `type name [= init];`
    Decl(Type, String, Option<Expr>),
    /// `name = e;` or `name op= e;`
    Assign(String, Option<BinOp>, Expr),
    /// `if (c) s [else s]`
    If(Expr, Box<Stmt>, Option<Box<Stmt>>),
    /// `for ([float] i = a; i cmp b; i += c) s`
    For {
        /// Loop variable.
        var: String,
        /// Declared in the header (`float i = …`).
        declared: bool,
        /// Start value.
        init: Expr,
        /// Comparison operator of the condition.
        cmp: BinOp,
        /// Bound compared against.
        bound: Expr,
        /// `+=` (1) or `-=` (−1).
        step_sign: f64,
        /// Step.
        step: Expr,
        /// Body.
        body: Box<Stmt>,
    },
    /// `return e;`
    Return(Expr),
    /// `{ … }`
    Block(Vec<Stmt>),
}

/// A user function.
#[derive(Clone, Debug, PartialEq)]
pub struct Function {
    /// Return type.
    pub ret: Type,
    /// Name.
    pub name: String,
    /// Parameters.
    pub params: Vec<(Type, String, Pos)>,
    /// Body.
    pub body: Vec<Stmt>,
    /// Where it starts.
    pub pos: Pos,
}

/// A shader parameter with its default.
#[derive(Clone, Debug, PartialEq)]
pub struct ShaderParam {
    /// Type.
    pub ty: Type,
    /// Name.
    pub name: String,
    /// Default value expression (constant).
    pub default: Expr,
    /// Where it is declared.
    pub pos: Pos,
}

/// A whole source file: functions and one shader.
#[derive(Clone, Debug, PartialEq)]
pub struct Program {
    /// User functions, in order.
    pub functions: Vec<Function>,
    /// Shader name.
    pub name: String,
    /// Shader parameters.
    pub params: Vec<ShaderParam>,
    /// Shader body.
    pub body: Vec<Stmt>,
}

struct Parser {
    toks: Vec<Token>,
    i: usize,
    /// Nesting depth of the tree under construction (see [`Parser::enter`]).
    depth: usize,
}

/// Parses a source file. Expressions and statements may nest at most
/// [`limits::MAX_NESTING_DEPTH`] levels (a chain of binary operators counts one level per
/// operator): the checker and interpreter recurse once per level, and that bound keeps their
/// stack use bounded.
pub fn parse(src: &str) -> Result<Program, ShaderError> {
    let mut p = Parser { toks: lex(src)?, i: 0, depth: 0 };
    p.program()
}

fn describe(t: &Tok) -> String {
    match t {
        Tok::Num(v) => format!("number {v}"),
        Tok::Ident(s) => format!("'{s}'"),
        Tok::Sym(s) => format!("'{s}'"),
        Tok::Eof => "end of file".to_string(),
    }
}

impl Parser {
    /// One level deeper into the tree; an error at `pos` past the ceiling. Callers restore
    /// `depth` on success; after an error the parse is abandoned, so it need not be.
    fn enter(&mut self, pos: Pos) -> Result<(), ShaderError> {
        self.depth += 1;
        if self.depth > limits::MAX_NESTING_DEPTH {
            return Err(ShaderError::at(
                pos,
                format!(
                    "nested deeper than {} levels (expressions, blocks and each operator of a chain count one level; \
                     split it with intermediate variables)",
                    limits::MAX_NESTING_DEPTH
                ),
            ));
        }
        Ok(())
    }

    fn peek(&self) -> &Tok {
        &self.toks[self.i].tok
    }
    fn peek_at(&self, k: usize) -> &Tok {
        &self.toks[(self.i + k).min(self.toks.len() - 1)].tok
    }
    fn pos(&self) -> Pos {
        self.toks[self.i].pos
    }
    fn bump(&mut self) -> Token {
        let t = self.toks[self.i].clone();
        if self.i + 1 < self.toks.len() {
            self.i += 1;
        }
        t
    }
    fn is_sym(&self, s: &str) -> bool {
        matches!(self.peek(), Tok::Sym(x) if *x == s)
    }
    fn eat(&mut self, s: &str) -> bool {
        if self.is_sym(s) {
            self.bump();
            true
        } else {
            false
        }
    }
    fn expect(&mut self, s: &str) -> Result<(), ShaderError> {
        if self.eat(s) {
            Ok(())
        } else {
            Err(ShaderError::at(self.pos(), format!("expected '{s}', found {}", describe(self.peek()))))
        }
    }
    fn ident(&mut self, what: &str) -> Result<(String, Pos), ShaderError> {
        let pos = self.pos();
        match self.peek().clone() {
            Tok::Ident(s) => {
                self.bump();
                Ok((s, pos))
            }
            t => Err(ShaderError::at(pos, format!("expected {what}, found {}", describe(&t)))),
        }
    }
    fn ty(&mut self) -> Result<Type, ShaderError> {
        let (name, pos) = self.ident("a type")?;
        Type::from_name(&name).ok_or_else(|| {
            ShaderError::at(pos, format!("expected a type (float, color, point, vector), found '{name}'"))
        })
    }

    fn program(&mut self) -> Result<Program, ShaderError> {
        let mut functions = Vec::new();
        let mut shader = None;
        while *self.peek() != Tok::Eof {
            let pos = self.pos();
            match self.peek().clone() {
                Tok::Ident(k) if k == "shader" || k == "surface" => {
                    if shader.is_some() {
                        return Err(ShaderError::at(pos, "a file holds one shader; found a second"));
                    }
                    self.bump();
                    let (name, _) = self.ident("the shader's name")?;
                    self.expect("(")?;
                    let mut params = Vec::new();
                    if !self.is_sym(")") {
                        loop {
                            let ppos = self.pos();
                            let ty = self.ty()?;
                            let (pname, _) = self.ident("a parameter name")?;
                            if !self.eat("=") {
                                return Err(ShaderError::at(
                                    self.pos(),
                                    format!("shader parameter '{pname}' needs a default value ('= …')"),
                                ));
                            }
                            let default = self.expr()?;
                            params.push(ShaderParam { ty, name: pname, default, pos: ppos });
                            if !self.eat(",") {
                                break;
                            }
                        }
                    }
                    self.expect(")")?;
                    let body = self.block()?;
                    shader = Some((name, params, body));
                }
                Tok::Ident(k) if Type::from_name(&k).is_some() => {
                    let ret = self.ty()?;
                    let (name, _) = self.ident("a function name")?;
                    self.expect("(")?;
                    let mut params = Vec::new();
                    if !self.is_sym(")") {
                        loop {
                            let ppos = self.pos();
                            let ty = self.ty()?;
                            let (pname, _) = self.ident("a parameter name")?;
                            params.push((ty, pname, ppos));
                            if !self.eat(",") {
                                break;
                            }
                        }
                    }
                    self.expect(")")?;
                    let body = self.block()?;
                    functions.push(Function { ret, name, params, body, pos });
                }
                t => {
                    return Err(ShaderError::at(
                        pos,
                        format!("expected a function or 'shader' definition, found {}", describe(&t)),
                    ))
                }
            }
        }
        let (name, params, body) =
            shader.ok_or_else(|| ShaderError::at(self.pos(), "no 'shader name(…) { … }' definition found"))?;
        Ok(Program { functions, name, params, body })
    }

    fn block(&mut self) -> Result<Vec<Stmt>, ShaderError> {
        self.expect("{")?;
        let mut out = Vec::new();
        while !self.is_sym("}") {
            if *self.peek() == Tok::Eof {
                return Err(ShaderError::at(self.pos(), "expected '}' before end of file"));
            }
            out.push(self.stmt()?);
        }
        self.bump();
        Ok(out)
    }

    fn stmt(&mut self) -> Result<Stmt, ShaderError> {
        let pos = self.pos();
        self.enter(pos)?;
        let s = self.stmt_inner(pos);
        self.depth -= 1;
        s
    }

    fn stmt_inner(&mut self, pos: Pos) -> Result<Stmt, ShaderError> {
        if self.is_sym("{") {
            return Ok(Stmt { kind: StmtKind::Block(self.block()?), pos });
        }
        let word = match self.peek().clone() {
            Tok::Ident(w) => w,
            t => return Err(ShaderError::at(pos, format!("expected a statement, found {}", describe(&t)))),
        };
        match word.as_str() {
            "if" => {
                self.bump();
                self.expect("(")?;
                let c = self.expr()?;
                self.expect(")")?;
                let then = Box::new(self.stmt()?);
                let other = if matches!(self.peek(), Tok::Ident(w) if w == "else") {
                    self.bump();
                    Some(Box::new(self.stmt()?))
                } else {
                    None
                };
                Ok(Stmt { kind: StmtKind::If(c, then, other), pos })
            }
            "for" => self.for_stmt(pos),
            "return" => {
                self.bump();
                let e = self.expr()?;
                self.expect(";")?;
                Ok(Stmt { kind: StmtKind::Return(e), pos })
            }
            _ if Type::from_name(&word).is_some() && matches!(self.peek_at(1), Tok::Ident(_)) => {
                let ty = self.ty()?;
                let (name, _) = self.ident("a variable name")?;
                let init = if self.eat("=") { Some(self.expr()?) } else { None };
                self.expect(";")?;
                Ok(Stmt { kind: StmtKind::Decl(ty, name, init), pos })
            }
            _ => {
                let (name, _) = self.ident("a statement")?;
                let op = match self.peek() {
                    Tok::Sym("=") => None,
                    Tok::Sym("+=") => Some(BinOp::Add),
                    Tok::Sym("-=") => Some(BinOp::Sub),
                    Tok::Sym("*=") => Some(BinOp::Mul),
                    Tok::Sym("/=") => Some(BinOp::Div),
                    t => {
                        return Err(ShaderError::at(
                            self.pos(),
                            format!("expected an assignment to '{name}' ('=', '+=', …), found {}", describe(t)),
                        ))
                    }
                };
                self.bump();
                let e = self.expr()?;
                self.expect(";")?;
                Ok(Stmt { kind: StmtKind::Assign(name, op, e), pos })
            }
        }
    }

    fn for_stmt(&mut self, pos: Pos) -> Result<Stmt, ShaderError> {
        self.bump();
        self.expect("(")?;
        let declared = matches!(self.peek(), Tok::Ident(w) if w == "float");
        if declared {
            self.bump();
        }
        let (var, _) = self.ident("the loop variable")?;
        self.expect("=")?;
        let init = self.expr()?;
        self.expect(";")?;
        let (v2, p2) = self.ident("the loop variable")?;
        if v2 != var {
            return Err(ShaderError::at(p2, format!("the loop condition must test '{var}', found '{v2}'")));
        }
        let cmp = match self.bump().tok {
            Tok::Sym("<") => BinOp::Lt,
            Tok::Sym("<=") => BinOp::Le,
            Tok::Sym(">") => BinOp::Gt,
            Tok::Sym(">=") => BinOp::Ge,
            t => {
                return Err(ShaderError::at(
                    p2,
                    format!("expected <, <=, > or >= in the loop condition, found {}", describe(&t)),
                ))
            }
        };
        let bound = self.expr()?;
        self.expect(";")?;
        let (v3, p3) = self.ident("the loop variable")?;
        if v3 != var {
            return Err(ShaderError::at(p3, format!("the loop step must update '{var}', found '{v3}'")));
        }
        let step_sign = match self.bump().tok {
            Tok::Sym("+=") => 1.0,
            Tok::Sym("-=") => -1.0,
            t => {
                return Err(ShaderError::at(p3, format!("expected += or -= in the loop step, found {}", describe(&t))))
            }
        };
        let step = self.expr()?;
        self.expect(")")?;
        let body = Box::new(self.stmt()?);
        Ok(Stmt { kind: StmtKind::For { var, declared, init, cmp, bound, step_sign, step, body }, pos })
    }

    fn expr(&mut self) -> Result<Expr, ShaderError> {
        self.enter(self.pos())?;
        let e = self.expr_inner();
        self.depth -= 1;
        e
    }

    fn expr_inner(&mut self) -> Result<Expr, ShaderError> {
        let c = self.binary(0)?;
        if self.is_sym("?") {
            let pos = c.pos;
            self.bump();
            let a = self.expr()?;
            self.expect(":")?;
            let b = self.expr()?;
            return Ok(Expr { kind: ExprKind::Ternary(Box::new(c), Box::new(a), Box::new(b)), pos });
        }
        Ok(c)
    }

    fn binop(&self) -> Option<(BinOp, u8)> {
        let Tok::Sym(s) = self.peek() else { return None };
        Some(match *s {
            "||" => (BinOp::Or, 1),
            "&&" => (BinOp::And, 2),
            "==" => (BinOp::Eq, 3),
            "!=" => (BinOp::Ne, 3),
            "<" => (BinOp::Lt, 4),
            "<=" => (BinOp::Le, 4),
            ">" => (BinOp::Gt, 4),
            ">=" => (BinOp::Ge, 4),
            "+" => (BinOp::Add, 5),
            "-" => (BinOp::Sub, 5),
            "*" => (BinOp::Mul, 6),
            "/" => (BinOp::Div, 6),
            _ => return None,
        })
    }

    /// Precedence climbing; all binary operators are left-associative.
    fn binary(&mut self, min_prec: u8) -> Result<Expr, ShaderError> {
        let mut lhs = self.unary()?;
        // Each operator of the chain puts the tree built so far one level deeper.
        let base = self.depth;
        while let Some((op, prec)) = self.binop() {
            if prec <= min_prec {
                break;
            }
            self.enter(self.pos())?;
            self.bump();
            let rhs = self.binary(prec)?;
            let pos = lhs.pos;
            lhs = Expr { kind: ExprKind::Binary(op, Box::new(lhs), Box::new(rhs)), pos };
        }
        self.depth = base;
        Ok(lhs)
    }

    fn unary(&mut self) -> Result<Expr, ShaderError> {
        let pos = self.pos();
        if matches!(self.peek(), Tok::Sym("-" | "+" | "!")) {
            self.enter(pos)?;
            let e = match self.bump().tok {
                Tok::Sym("-") => Expr { kind: ExprKind::Neg(Box::new(self.unary()?)), pos },
                Tok::Sym("!") => Expr { kind: ExprKind::Not(Box::new(self.unary()?)), pos },
                _ => self.unary()?,
            };
            self.depth -= 1;
            return Ok(e);
        }
        let mut e = self.primary()?;
        let base = self.depth;
        while self.is_sym(".") {
            self.enter(self.pos())?;
            self.bump();
            let (m, _) = self.ident("a component name (x, y, z, r, g, b)")?;
            let epos = e.pos;
            e = Expr { kind: ExprKind::Member(Box::new(e), m), pos: epos };
        }
        self.depth = base;
        Ok(e)
    }

    fn primary(&mut self) -> Result<Expr, ShaderError> {
        let pos = self.pos();
        match self.peek().clone() {
            Tok::Num(v) => {
                self.bump();
                Ok(Expr { kind: ExprKind::Num(v), pos })
            }
            Tok::Ident(name) => {
                self.bump();
                if self.eat("(") {
                    let mut args = Vec::new();
                    if !self.is_sym(")") {
                        loop {
                            args.push(self.expr()?);
                            if !self.eat(",") {
                                break;
                            }
                        }
                    }
                    self.expect(")")?;
                    Ok(Expr { kind: ExprKind::Call(name, args), pos })
                } else {
                    Ok(Expr { kind: ExprKind::Var(name), pos })
                }
            }
            Tok::Sym("(") => {
                self.bump();
                let e = self.expr()?;
                self.expect(")")?;
                Ok(e)
            }
            t => Err(ShaderError::at(pos, format!("expected an expression, found {}", describe(&t)))),
        }
    }
}
