//! Name resolution and type checking: turns the syntax tree into the resolved program the
//! interpreter runs (variables become frame slots, calls become builtins or function indices,
//! float→triple promotions become explicit). Errors carry line and column.

use super::lexer::Pos;
use super::parser::{BinOp, Expr, ExprKind, Program, Stmt, StmtKind, Type};
use super::ShaderError;

/// The type of a value, including the condition type of comparisons.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VTy {
    /// A number.
    Float,
    /// A triple: color, point or vector.
    Triple(Type),
    /// The (three-valued) result of a comparison.
    Bool,
}

impl VTy {
    fn of(t: Type) -> VTy {
        if t == Type::Float {
            VTy::Float
        } else {
            VTy::Triple(t)
        }
    }
    fn name(self) -> &'static str {
        match self {
            VTy::Float => "float",
            VTy::Triple(t) => t.name(),
            VTy::Bool => "condition",
        }
    }
}

/// Global inputs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Global {
    /// Surface parameter u (lat-long: φ/2π).
    U,
    /// Surface parameter v (lat-long: θ/π).
    V,
    /// Size of the sample region in u.
    Du,
    /// Size of the sample region in v.
    Dv,
    /// Position: (u, v, 0), or the direction in lat-long mode.
    P,
    /// Direction (lat-long mode); (0, 0, 1) otherwise.
    D,
    /// Output colour.
    Ci,
}

/// Arithmetic operators (componentwise, floats broadcast).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ArOp {
    /// +
    Add,
    /// −
    Sub,
    /// ×
    Mul,
    /// ÷ (x/0 = 0)
    Div,
}

/// Comparison operators on floats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CmpOp {
    /// <
    Lt,
    /// <=
    Le,
    /// >
    Gt,
    /// >=
    Ge,
    /// ==
    Eq,
    /// !=
    Ne,
}

/// Builtin functions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[allow(missing_docs)]
pub enum Builtin {
    Sin,
    Cos,
    Sqrt,
    Exp,
    Log,
    Abs,
    Floor,
    Ceil,
    Fract,
    Pow,
    Min,
    Max,
    Mod,
    Step,
    Clamp,
    Mix,
    Smoothstep,
    Noise,
    Snoise,
    Fbm,
    Turbulence,
    Spline,
    Length,
    Dot,
    Distance,
    Normalize,
    Cross,
    Xcomp,
    Ycomp,
    Zcomp,
    Luminance,
}

/// A resolved expression.
#[derive(Clone, Debug, PartialEq)]
pub enum IExpr {
    /// Constant.
    Const(f64),
    /// Frame slot.
    Local(usize),
    /// Global input.
    Global(Global),
    /// Negation.
    Neg(Box<IExpr>),
    /// Arithmetic.
    Arith(ArOp, Box<IExpr>, Box<IExpr>),
    /// Comparison of floats.
    Cmp(CmpOp, Box<IExpr>, Box<IExpr>),
    /// Logical and.
    And(Box<IExpr>, Box<IExpr>),
    /// Logical or.
    Or(Box<IExpr>, Box<IExpr>),
    /// Logical not.
    Not(Box<IExpr>),
    /// `c ? a : b`
    Select(Box<IExpr>, Box<IExpr>, Box<IExpr>),
    /// Builtin call.
    Builtin(Builtin, Vec<IExpr>),
    /// User function call (index, arguments, call site).
    User(usize, Vec<IExpr>, Pos),
    /// Triple from one (broadcast) or three floats.
    Construct(Vec<IExpr>),
    /// One component of a triple.
    Component(Box<IExpr>, usize),
}

/// A resolved statement.
#[derive(Clone, Debug, PartialEq)]
pub enum IStmt {
    /// Slot = value.
    Assign(usize, IExpr),
    /// Ci = value.
    SetCi(IExpr),
    /// Condition, then, else.
    If(IExpr, Vec<IStmt>, Vec<IStmt>),
    /// Counted loop with constant bounds.
    For {
        /// Loop variable slot.
        slot: usize,
        /// Start.
        init: IExpr,
        /// Comparison.
        cmp: CmpOp,
        /// Bound.
        bound: IExpr,
        /// Signed step.
        step: IExpr,
        /// Body.
        body: Vec<IStmt>,
        /// Where the loop is.
        pos: Pos,
    },
    /// Return (the last statement of a function).
    Return(IExpr),
    /// A nested block.
    Block(Vec<IStmt>),
}

/// A resolved user function.
#[derive(Clone, Debug, PartialEq)]
pub struct IFunction {
    /// Name.
    pub name: String,
    /// Parameter count (slots 0..n).
    pub params: usize,
    /// Frame size.
    pub slots: usize,
    /// Body.
    pub body: Vec<IStmt>,
}

/// A shader parameter after checking.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamInfo {
    /// Name.
    pub name: String,
    /// Type.
    pub ty: Type,
    /// Default expression (constant; may use earlier parameters).
    pub default: IExpr,
}

/// A checked program.
#[derive(Clone, Debug, PartialEq)]
pub struct Checked {
    /// Shader name.
    pub name: String,
    /// Parameters (slots 0..n of the shader frame).
    pub params: Vec<ParamInfo>,
    /// Shader frame size.
    pub slots: usize,
    /// Shader body.
    pub body: Vec<IStmt>,
    /// User functions.
    pub functions: Vec<IFunction>,
    /// Whether the shader reads D (then it is meant for `--latlong`).
    pub uses_direction: bool,
}

#[derive(Clone)]
struct Var {
    name: String,
    ty: VTy,
    slot: usize,
    /// Parameters and loop variables: usable in loop bounds, read-only.
    konst: bool,
}

struct Scope {
    vars: Vec<Var>,
    marks: Vec<usize>,
    slots: usize,
    in_shader: bool,
}

impl Scope {
    fn lookup(&self, name: &str) -> Option<&Var> {
        self.vars.iter().rev().find(|v| v.name == name)
    }
    fn declare(&mut self, name: &str, ty: VTy, konst: bool, pos: Pos) -> Result<usize, ShaderError> {
        let start = *self.marks.last().unwrap_or(&0);
        if self.vars[start..].iter().any(|v| v.name == name) {
            return Err(ShaderError::at(pos, format!("'{name}' is already declared in this block")));
        }
        if global_of(name).is_some() || builtin_of(name).is_some() || Type::from_name(name).is_some() {
            return Err(ShaderError::at(pos, format!("'{name}' is a reserved name")));
        }
        let slot = self.slots;
        self.slots += 1;
        self.vars.push(Var { name: name.to_string(), ty, slot, konst });
        Ok(slot)
    }
    fn push(&mut self) {
        self.marks.push(self.vars.len());
    }
    fn pop(&mut self) {
        let m = self.marks.pop().unwrap_or(0);
        self.vars.truncate(m);
    }
}

fn global_of(name: &str) -> Option<(Global, VTy)> {
    Some(match name {
        "u" => (Global::U, VTy::Float),
        "v" => (Global::V, VTy::Float),
        "du" => (Global::Du, VTy::Float),
        "dv" => (Global::Dv, VTy::Float),
        "P" => (Global::P, VTy::Triple(Type::Point)),
        "D" => (Global::D, VTy::Triple(Type::Vector)),
        "Ci" => (Global::Ci, VTy::Triple(Type::Color)),
        _ => return None,
    })
}

fn builtin_of(name: &str) -> Option<Builtin> {
    use Builtin::*;
    Some(match name {
        "sin" => Sin,
        "cos" => Cos,
        "sqrt" => Sqrt,
        "exp" => Exp,
        "log" => Log,
        "abs" => Abs,
        "floor" => Floor,
        "ceil" => Ceil,
        "fract" => Fract,
        "pow" => Pow,
        "min" => Min,
        "max" => Max,
        "mod" => Mod,
        "step" => Step,
        "clamp" => Clamp,
        "mix" => Mix,
        "smoothstep" => Smoothstep,
        "noise" => Noise,
        "snoise" => Snoise,
        "fbm" => Fbm,
        "turbulence" => Turbulence,
        "spline" => Spline,
        "length" => Length,
        "dot" => Dot,
        "distance" => Distance,
        "normalize" => Normalize,
        "cross" => Cross,
        "xcomp" => Xcomp,
        "ycomp" => Ycomp,
        "zcomp" => Zcomp,
        "luminance" => Luminance,
        _ => return None,
    })
}

/// Names of all builtins (for docs and messages).
pub const BUILTINS: &[&str] = &[
    "sin",
    "cos",
    "sqrt",
    "exp",
    "log",
    "abs",
    "floor",
    "ceil",
    "fract",
    "pow",
    "min",
    "max",
    "mod",
    "step",
    "clamp",
    "mix",
    "smoothstep",
    "noise",
    "snoise",
    "fbm",
    "turbulence",
    "spline",
    "length",
    "dot",
    "distance",
    "normalize",
    "cross",
    "xcomp",
    "ycomp",
    "zcomp",
    "luminance",
];

struct Checker<'a> {
    prog: &'a Program,
    uses_direction: bool,
}

/// Type of a componentwise result; float operands broadcast; color never mixes with point/vector.
fn unify(a: VTy, b: VTy, pos: Pos, what: &str) -> Result<VTy, ShaderError> {
    match (a, b) {
        (VTy::Bool, _) | (_, VTy::Bool) => {
            Err(ShaderError::at(pos, format!("{what}: a condition cannot be used as a number")))
        }
        (VTy::Float, t) | (t, VTy::Float) => Ok(t),
        (VTy::Triple(Type::Color), VTy::Triple(Type::Color)) => Ok(a),
        (VTy::Triple(Type::Color), VTy::Triple(t)) | (VTy::Triple(t), VTy::Triple(Type::Color)) => {
            Err(ShaderError::at(pos, format!("{what}: cannot combine color and {} (convert explicitly)", t.name())))
        }
        (VTy::Triple(x), VTy::Triple(y)) => {
            Ok(VTy::Triple(if x == Type::Point || y == Type::Point { Type::Point } else { Type::Vector }))
        }
    }
}

/// Converts `e` of type `from` to `to` for an assignment or argument, or explains why not.
fn coerce(e: IExpr, from: VTy, to: VTy, pos: Pos, what: &str) -> Result<IExpr, ShaderError> {
    match (from, to) {
        _ if from == to => Ok(e),
        (VTy::Float, VTy::Triple(_)) => Ok(IExpr::Construct(vec![e])),
        (VTy::Triple(Type::Point | Type::Vector), VTy::Triple(Type::Point | Type::Vector)) => Ok(e),
        _ => Err(ShaderError::at(pos, format!("{what}: expected {}, found {}", to.name(), from.name()))),
    }
}

impl Checker<'_> {
    fn is_const(&self, e: &Expr, sc: &Scope) -> bool {
        match &e.kind {
            ExprKind::Num(_) => true,
            ExprKind::Var(n) => sc.lookup(n).is_some_and(|v| v.konst),
            ExprKind::Call(name, args) => {
                (builtin_of(name).is_some() || Type::from_name(name).is_some())
                    && args.iter().all(|a| self.is_const(a, sc))
            }
            ExprKind::Neg(a) | ExprKind::Not(a) | ExprKind::Member(a, _) => self.is_const(a, sc),
            ExprKind::Binary(_, a, b) => self.is_const(a, sc) && self.is_const(b, sc),
            ExprKind::Ternary(c, a, b) => self.is_const(c, sc) && self.is_const(a, sc) && self.is_const(b, sc),
        }
    }

    fn expr(&mut self, e: &Expr, sc: &Scope) -> Result<(IExpr, VTy), ShaderError> {
        let pos = e.pos;
        Ok(match &e.kind {
            ExprKind::Num(v) => (IExpr::Const(*v), VTy::Float),
            ExprKind::Var(name) => {
                if let Some(v) = sc.lookup(name) {
                    (IExpr::Local(v.slot), v.ty)
                } else if let Some((g, ty)) = global_of(name) {
                    if g == Global::D {
                        self.uses_direction = true;
                    }
                    (IExpr::Global(g), ty)
                } else {
                    return Err(ShaderError::at(pos, format!("unknown variable '{name}'")));
                }
            }
            ExprKind::Neg(a) => {
                let (a, t) = self.expr(a, sc)?;
                if t == VTy::Bool {
                    return Err(ShaderError::at(pos, "cannot negate a condition (use '!')"));
                }
                (IExpr::Neg(Box::new(a)), t)
            }
            ExprKind::Not(a) => {
                let (a, t) = self.expr(a, sc)?;
                if t != VTy::Bool {
                    return Err(ShaderError::at(pos, format!("'!' needs a condition, found {}", t.name())));
                }
                (IExpr::Not(Box::new(a)), VTy::Bool)
            }
            ExprKind::Member(a, m) => {
                let (a, t) = self.expr(a, sc)?;
                let VTy::Triple(tt) = t else {
                    return Err(ShaderError::at(
                        pos,
                        format!("'.{m}' needs a color, point or vector, found {}", t.name()),
                    ));
                };
                let idx = match (tt, m.as_str()) {
                    (Type::Color, "r") | (Type::Point | Type::Vector, "x") => 0,
                    (Type::Color, "g") | (Type::Point | Type::Vector, "y") => 1,
                    (Type::Color, "b") | (Type::Point | Type::Vector, "z") => 2,
                    _ => return Err(ShaderError::at(pos, format!("{} has no component '{m}'", tt.name()))),
                };
                (IExpr::Component(Box::new(a), idx), VTy::Float)
            }
            ExprKind::Binary(op, a, b) => {
                let (ia, ta) = self.expr(a, sc)?;
                let (ib, tb) = self.expr(b, sc)?;
                match op {
                    BinOp::And | BinOp::Or => {
                        if ta != VTy::Bool || tb != VTy::Bool {
                            return Err(ShaderError::at(pos, "'&&' and '||' need conditions on both sides"));
                        }
                        let (a, b) = (Box::new(ia), Box::new(ib));
                        (if *op == BinOp::And { IExpr::And(a, b) } else { IExpr::Or(a, b) }, VTy::Bool)
                    }
                    BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge | BinOp::Eq | BinOp::Ne => {
                        if ta != VTy::Float || tb != VTy::Float {
                            return Err(ShaderError::at(
                                pos,
                                format!(
                                    "comparisons need floats, found {} and {} (compare components)",
                                    ta.name(),
                                    tb.name()
                                ),
                            ));
                        }
                        let c = match op {
                            BinOp::Lt => CmpOp::Lt,
                            BinOp::Le => CmpOp::Le,
                            BinOp::Gt => CmpOp::Gt,
                            BinOp::Ge => CmpOp::Ge,
                            BinOp::Eq => CmpOp::Eq,
                            _ => CmpOp::Ne,
                        };
                        (IExpr::Cmp(c, Box::new(ia), Box::new(ib)), VTy::Bool)
                    }
                    _ => {
                        let sym = match op {
                            BinOp::Add => "+",
                            BinOp::Sub => "-",
                            BinOp::Mul => "*",
                            _ => "/",
                        };
                        let mut t = unify(ta, tb, pos, &format!("operator '{sym}'"))?;
                        if *op == BinOp::Sub && ta == VTy::Triple(Type::Point) && tb == VTy::Triple(Type::Point) {
                            t = VTy::Triple(Type::Vector);
                        }
                        let o = match op {
                            BinOp::Add => ArOp::Add,
                            BinOp::Sub => ArOp::Sub,
                            BinOp::Mul => ArOp::Mul,
                            _ => ArOp::Div,
                        };
                        (IExpr::Arith(o, Box::new(ia), Box::new(ib)), t)
                    }
                }
            }
            ExprKind::Ternary(c, a, b) => {
                let (ic, tc) = self.expr(c, sc)?;
                if tc != VTy::Bool {
                    return Err(ShaderError::at(pos, format!("'?' needs a condition, found {}", tc.name())));
                }
                let (ia, ta) = self.expr(a, sc)?;
                let (ib, tb) = self.expr(b, sc)?;
                let t = unify(ta, tb, pos, "'?:'")?;
                let ia = coerce(ia, ta, t, pos, "'?:'")?;
                let ib = coerce(ib, tb, t, pos, "'?:'")?;
                (IExpr::Select(Box::new(ic), Box::new(ia), Box::new(ib)), t)
            }
            ExprKind::Call(name, args) => self.call(name, args, pos, sc)?,
        })
    }

    fn call(&mut self, name: &str, args: &[Expr], pos: Pos, sc: &Scope) -> Result<(IExpr, VTy), ShaderError> {
        let mut checked = Vec::with_capacity(args.len());
        for a in args {
            checked.push(self.expr(a, sc)?);
        }
        let n = args.len();
        let arity = |lo: usize, hi: usize| -> Result<(), ShaderError> {
            if n < lo || n > hi {
                let want = if lo == hi { format!("{lo}") } else { format!("{lo} to {hi}") };
                Err(ShaderError::at(pos, format!("'{name}' takes {want} arguments, found {n}")))
            } else {
                Ok(())
            }
        };
        let no_bool = |c: &[(IExpr, VTy)]| -> Result<(), ShaderError> {
            if c.iter().any(|(_, t)| *t == VTy::Bool) {
                return Err(ShaderError::at(pos, format!("'{name}': a condition cannot be an argument")));
            }
            Ok(())
        };
        no_bool(&checked)?;
        if let Some(t) = Type::from_name(name) {
            if t == Type::Float {
                arity(1, 1)?;
                let (e, ty) = checked.remove(0);
                return match ty {
                    VTy::Float => Ok((e, VTy::Float)),
                    _ => Err(ShaderError::at(pos, "float(…) needs a float (use xcomp or .x for a component)")),
                };
            }
            if n != 1 && n != 3 {
                return Err(ShaderError::at(pos, format!("{name}(…) takes 1 or 3 floats, found {n} arguments")));
            }
            if n == 1 {
                let (e, ty) = checked.remove(0);
                return match ty {
                    VTy::Float => Ok((IExpr::Construct(vec![e]), VTy::Triple(t))),
                    // An explicit constructor converts between triple types.
                    VTy::Triple(_) => Ok((e, VTy::Triple(t))),
                    VTy::Bool => Err(ShaderError::at(pos, "a condition cannot be converted")),
                };
            }
            for (i, (_, ty)) in checked.iter().enumerate() {
                if *ty != VTy::Float {
                    return Err(ShaderError::at(
                        pos,
                        format!("{name}(…): argument {} must be float, found {}", i + 1, ty.name()),
                    ));
                }
            }
            return Ok((IExpr::Construct(checked.into_iter().map(|c| c.0).collect()), VTy::Triple(t)));
        }
        if let Some(b) = builtin_of(name) {
            return self.builtin(b, name, checked, args, pos, sc, arity);
        }
        let Some(fi) = self.prog.functions.iter().position(|f| f.name == name) else {
            return Err(ShaderError::at(pos, format!("unknown function '{name}'")));
        };
        let f = &self.prog.functions[fi];
        if f.params.len() != n {
            return Err(ShaderError::at(pos, format!("'{name}' takes {} arguments, found {n}", f.params.len())));
        }
        let mut out = Vec::with_capacity(n);
        for (i, ((e, ty), (pty, pname, _))) in checked.into_iter().zip(&f.params).enumerate() {
            out.push(coerce(e, ty, VTy::of(*pty), args[i].pos, &format!("argument '{pname}' of '{name}'"))?);
        }
        Ok((IExpr::User(fi, out, pos), VTy::of(f.ret)))
    }

    #[allow(clippy::too_many_arguments)]
    fn builtin(
        &mut self,
        b: Builtin,
        name: &str,
        checked: Vec<(IExpr, VTy)>,
        args: &[Expr],
        pos: Pos,
        sc: &Scope,
        arity: impl Fn(usize, usize) -> Result<(), ShaderError>,
    ) -> Result<(IExpr, VTy), ShaderError> {
        use Builtin::*;
        let types: Vec<VTy> = checked.iter().map(|c| c.1).collect();
        let widest = |types: &[VTy]| -> Result<VTy, ShaderError> {
            let mut t = VTy::Float;
            for &x in types {
                t = unify(t, x, pos, &format!("'{name}'"))?;
            }
            Ok(t)
        };
        let need_triple = |i: usize| -> Result<(), ShaderError> {
            match types[i] {
                VTy::Triple(_) => Ok(()),
                t => Err(ShaderError::at(
                    pos,
                    format!("'{name}': argument {} must be a color, point or vector, found {}", i + 1, t.name()),
                )),
            }
        };
        let need_float = |i: usize| -> Result<(), ShaderError> {
            if types[i] == VTy::Float {
                Ok(())
            } else {
                Err(ShaderError::at(
                    pos,
                    format!("'{name}': argument {} must be float, found {}", i + 1, types[i].name()),
                ))
            }
        };
        let ty = match b {
            Sin | Cos | Sqrt | Exp | Log | Abs | Floor | Ceil | Fract => {
                arity(1, 1)?;
                types[0]
            }
            Pow | Min | Max | Mod | Step => {
                arity(2, 2)?;
                widest(&types)?
            }
            Clamp | Mix | Smoothstep => {
                arity(3, 3)?;
                widest(&types)?
            }
            Noise | Snoise => {
                arity(1, 2)?;
                match (types.len(), types[0]) {
                    (1, VTy::Float) => {}
                    (1, VTy::Triple(Type::Point | Type::Vector)) => {}
                    (2, _) => {
                        need_float(0)?;
                        need_float(1)?;
                    }
                    _ => return Err(ShaderError::at(pos, format!("'{name}' takes a float, two floats, or a point"))),
                }
                VTy::Float
            }
            Fbm | Turbulence => {
                arity(1, 4)?;
                if !matches!(types[0], VTy::Triple(Type::Point | Type::Vector)) {
                    return Err(ShaderError::at(pos, format!("'{name}': argument 1 must be a point")));
                }
                for i in 1..types.len() {
                    need_float(i)?;
                }
                if args.len() > 1 && !self.is_const(&args[1], sc) {
                    return Err(ShaderError::at(
                        args[1].pos,
                        format!("'{name}': the octave count must be constant (literals, parameters, loop variables)"),
                    ));
                }
                VTy::Float
            }
            Spline => {
                if checked.len() < 5 {
                    return Err(ShaderError::at(pos, "'spline' takes a parameter and at least 4 knots"));
                }
                need_float(0)?;
                let t = widest(&types[1..])?;
                if matches!(t, VTy::Triple(Type::Point | Type::Vector)) {
                    return Err(ShaderError::at(pos, "'spline' knots must be floats or colors"));
                }
                t
            }
            Length | Normalize | Xcomp | Ycomp | Zcomp | Luminance => {
                arity(1, 1)?;
                need_triple(0)?;
                match b {
                    Normalize => types[0],
                    _ => VTy::Float,
                }
            }
            Dot | Distance | Cross => {
                arity(2, 2)?;
                need_triple(0)?;
                need_triple(1)?;
                widest(&types)?;
                if b == Cross {
                    VTy::Triple(Type::Vector)
                } else {
                    VTy::Float
                }
            }
        };
        // Promote float arguments of componentwise functions to the result's triple type.
        let promote = matches!(b, Pow | Min | Max | Mod | Step | Clamp | Mix | Smoothstep | Spline);
        let mut out = Vec::with_capacity(checked.len());
        for (i, (e, t)) in checked.into_iter().enumerate() {
            let keep = b == Spline && i == 0;
            out.push(if promote && !keep && t == VTy::Float && matches!(ty, VTy::Triple(_)) {
                IExpr::Construct(vec![e])
            } else {
                e
            });
        }
        Ok((IExpr::Builtin(b, out), ty))
    }

    fn stmts(&mut self, body: &[Stmt], sc: &mut Scope, in_function: bool) -> Result<Vec<IStmt>, ShaderError> {
        let mut out = Vec::new();
        for s in body {
            out.push(self.stmt(s, sc, in_function)?);
        }
        Ok(out)
    }

    fn stmt(&mut self, s: &Stmt, sc: &mut Scope, in_function: bool) -> Result<IStmt, ShaderError> {
        let pos = s.pos;
        Ok(match &s.kind {
            StmtKind::Decl(ty, name, init) => {
                let value = match init {
                    Some(e) => {
                        let (ie, t) = self.expr(e, sc)?;
                        coerce(ie, t, VTy::of(*ty), e.pos, &format!("initial value of '{name}'"))?
                    }
                    None if *ty == Type::Float => IExpr::Const(0.0),
                    None => IExpr::Construct(vec![IExpr::Const(0.0)]),
                };
                let slot = sc.declare(name, VTy::of(*ty), false, pos)?;
                IStmt::Assign(slot, value)
            }
            StmtKind::Assign(name, op, e) => {
                let (mut ie, mut t) = self.expr(e, sc)?;
                let (target, tty) = if let Some(v) = sc.lookup(name) {
                    if v.konst {
                        return Err(ShaderError::at(
                            pos,
                            format!("'{name}' is a parameter or loop variable and cannot be assigned"),
                        ));
                    }
                    (Some(v.slot), v.ty)
                } else if name == "Ci" {
                    if !sc.in_shader {
                        return Err(ShaderError::at(pos, "'Ci' can only be set in the shader body"));
                    }
                    (None, VTy::Triple(Type::Color))
                } else if global_of(name).is_some() {
                    return Err(ShaderError::at(pos, format!("the global '{name}' is read-only")));
                } else {
                    return Err(ShaderError::at(pos, format!("unknown variable '{name}'")));
                };
                if let Some(op) = op {
                    let cur = match target {
                        Some(slot) => IExpr::Local(slot),
                        None => IExpr::Global(Global::Ci),
                    };
                    t = unify(tty, t, pos, "compound assignment")?;
                    let o = match op {
                        BinOp::Add => ArOp::Add,
                        BinOp::Sub => ArOp::Sub,
                        BinOp::Mul => ArOp::Mul,
                        _ => ArOp::Div,
                    };
                    ie = IExpr::Arith(o, Box::new(cur), Box::new(ie));
                }
                let ie = coerce(ie, t, tty, e.pos, &format!("assignment to '{name}'"))?;
                match target {
                    Some(slot) => IStmt::Assign(slot, ie),
                    None => IStmt::SetCi(ie),
                }
            }
            StmtKind::If(c, a, b) => {
                let (ic, tc) = self.expr(c, sc)?;
                if tc != VTy::Bool {
                    return Err(ShaderError::at(
                        c.pos,
                        format!("'if' needs a condition (a comparison), found {}", tc.name()),
                    ));
                }
                sc.push();
                let ia = self.stmt_block(a, sc, in_function)?;
                sc.pop();
                sc.push();
                let ib = match b {
                    Some(b) => self.stmt_block(b, sc, in_function)?,
                    None => Vec::new(),
                };
                sc.pop();
                IStmt::If(ic, ia, ib)
            }
            StmtKind::For { var, declared, init, cmp, bound, step_sign, step, body } => {
                for (what, e) in [("start", init), ("bound", bound), ("step", step)] {
                    if !self.is_const(e, sc) {
                        return Err(ShaderError::at(
                            e.pos,
                            format!(
                                "the loop {what} must be constant (literals, parameters, enclosing loop variables)"
                            ),
                        ));
                    }
                }
                let (ii, ti) = self.expr(init, sc)?;
                let (ib, tb) = self.expr(bound, sc)?;
                let (is, ts) = self.expr(step, sc)?;
                if ti != VTy::Float || tb != VTy::Float || ts != VTy::Float {
                    return Err(ShaderError::at(pos, "loop start, bound and step must be floats"));
                }
                sc.push();
                let slot = if *declared {
                    sc.declare(var, VTy::Float, true, pos)?
                } else {
                    return Err(ShaderError::at(
                        pos,
                        format!("declare the loop variable in the loop: 'for (float {var} = …'"),
                    ));
                };
                let ibody = self.stmt_block(body, sc, in_function)?;
                sc.pop();
                let c = match cmp {
                    BinOp::Lt => CmpOp::Lt,
                    BinOp::Le => CmpOp::Le,
                    BinOp::Gt => CmpOp::Gt,
                    _ => CmpOp::Ge,
                };
                let step = if *step_sign < 0.0 { IExpr::Neg(Box::new(is)) } else { is };
                IStmt::For { slot, init: ii, cmp: c, bound: ib, step, body: ibody, pos }
            }
            StmtKind::Return(_) => {
                return Err(ShaderError::at(
                    pos,
                    if in_function {
                        "'return' must be the last statement of a function (assign to a variable in branches)"
                    } else {
                        "'return' is not allowed in the shader body (set Ci)"
                    },
                ))
            }
            StmtKind::Block(b) => {
                sc.push();
                let v = self.stmts(b, sc, in_function)?;
                sc.pop();
                IStmt::Block(v)
            }
        })
    }

    fn stmt_block(&mut self, s: &Stmt, sc: &mut Scope, in_function: bool) -> Result<Vec<IStmt>, ShaderError> {
        match &s.kind {
            StmtKind::Block(b) => self.stmts(b, sc, in_function),
            _ => Ok(vec![self.stmt(s, sc, in_function)?]),
        }
    }
}

/// Checks a parsed program.
pub fn check(prog: &Program) -> Result<Checked, ShaderError> {
    let mut ck = Checker { prog, uses_direction: false };
    for (i, f) in prog.functions.iter().enumerate() {
        if prog.functions[..i].iter().any(|g| g.name == f.name) {
            return Err(ShaderError::at(f.pos, format!("function '{}' is defined twice", f.name)));
        }
        if builtin_of(&f.name).is_some() || Type::from_name(&f.name).is_some() {
            return Err(ShaderError::at(f.pos, format!("'{}' is a builtin and cannot be redefined", f.name)));
        }
    }
    let mut functions = Vec::new();
    for f in &prog.functions {
        let mut sc = Scope { vars: Vec::new(), marks: vec![0], slots: 0, in_shader: false };
        for (ty, name, pos) in &f.params {
            // Function parameters are ordinary (assignable, non-constant) locals.
            sc.declare(name, VTy::of(*ty), false, *pos)?;
        }
        let Some((last, init)) = f.body.split_last() else {
            return Err(ShaderError::at(f.pos, format!("function '{}' must end with 'return …;'", f.name)));
        };
        let StmtKind::Return(ret) = &last.kind else {
            return Err(ShaderError::at(last.pos, format!("function '{}' must end with 'return …;'", f.name)));
        };
        let mut body = ck.stmts(init, &mut sc, true)?;
        let (ie, t) = ck.expr(ret, &sc)?;
        body.push(IStmt::Return(coerce(ie, t, VTy::of(f.ret), ret.pos, &format!("return value of '{}'", f.name))?));
        functions.push(IFunction { name: f.name.clone(), params: f.params.len(), slots: sc.slots, body });
    }
    let mut sc = Scope { vars: Vec::new(), marks: vec![0], slots: 0, in_shader: true };
    let mut params = Vec::new();
    for p in &prog.params {
        if !ck.is_const(&p.default, &sc) {
            return Err(ShaderError::at(p.default.pos, format!("the default of '{}' must be constant", p.name)));
        }
        let (ie, t) = ck.expr(&p.default, &sc)?;
        let default = coerce(ie, t, VTy::of(p.ty), p.default.pos, &format!("default of '{}'", p.name))?;
        sc.declare(&p.name, VTy::of(p.ty), true, p.pos)?;
        params.push(ParamInfo { name: p.name.clone(), ty: p.ty, default });
    }
    sc.push();
    let body = ck.stmts(&prog.body, &mut sc, false)?;
    Ok(Checked { name: prog.name.clone(), params, slots: sc.slots, body, functions, uses_direction: ck.uses_direction })
}
