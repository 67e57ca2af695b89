//! The interpreter: one implementation, generic over the number type (`f64` point sampling,
//! `Interval` and `Affine` area sampling).
//!
//! Conditions are three-valued. When a condition is ambiguous over the sample's range (both
//! outcomes occur), both branches run on copies of the frame and every variable (and `Ci`)
//! is joined afterwards (`Real::join`): the result bounds whichever branch the point
//! evaluation would take.

use super::check::{ArOp, Builtin, Checked, CmpOp, Global, IExpr, IStmt};
use super::lexer::Pos;
use super::noise;
use super::ShaderError;
use crate::affine::{Real, Sign};

pub use crate::limits::{MAX_CALL_DEPTH, MAX_EVALUATION_DEPTH, MAX_LOOP_ITERATIONS, MAX_OCTAVES, MAX_OPERATIONS};

/// What one noise evaluation counts against [`MAX_OPERATIONS`]: in affine arithmetic one costs
/// about 40 µs (a Taylor bound per cell part over up to 27 sub-boxes; measured, 12 000 of them
/// in 0.5 s), as much as ~1000 other operations (30 ns each), so the budget bounds the time of
/// a sample whatever mix of operations spends it.
const NOISE_OPERATIONS: u64 = 1024;

/// A three-valued truth.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tri {
    /// True over the whole range.
    True,
    /// False over the whole range.
    False,
    /// Both occur.
    Both,
}

impl Tri {
    fn not(self) -> Tri {
        match self {
            Tri::True => Tri::False,
            Tri::False => Tri::True,
            Tri::Both => Tri::Both,
        }
    }
    fn and(self, o: Tri) -> Tri {
        match (self, o) {
            (Tri::False, _) | (_, Tri::False) => Tri::False,
            (Tri::True, Tri::True) => Tri::True,
            _ => Tri::Both,
        }
    }
    fn or(self, o: Tri) -> Tri {
        self.not().and(o.not()).not()
    }
}

/// A runtime value.
#[derive(Clone, Debug, PartialEq)]
pub enum Value<N> {
    /// A float.
    F(N),
    /// A color, point or vector.
    T([N; 3]),
    /// A condition.
    B(Tri),
}

/// The global inputs of one evaluation.
#[derive(Clone, Debug)]
pub struct Globals<N> {
    /// u.
    pub u: N,
    /// v.
    pub v: N,
    /// du.
    pub du: N,
    /// dv.
    pub dv: N,
    /// P.
    pub p: [N; 3],
    /// D.
    pub d: [N; 3],
}

impl<N: Real> Value<N> {
    fn float(self) -> N {
        match self {
            Value::F(x) => x,
            Value::T(t) => t[0].clone(),
            Value::B(_) => N::constant(0.0),
        }
    }
    fn triple(self) -> [N; 3] {
        match self {
            Value::T(t) => t,
            Value::F(x) => [x.clone(), x.clone(), x],
            Value::B(_) => std::array::from_fn(|_| N::constant(0.0)),
        }
    }
    fn tri(&self) -> Tri {
        match self {
            Value::B(t) => *t,
            _ => Tri::Both,
        }
    }
    fn join(&self, o: &Value<N>) -> Value<N> {
        match (self, o) {
            (Value::F(a), Value::F(b)) => Value::F(a.join(b)),
            (Value::T(a), Value::T(b)) => Value::T(std::array::from_fn(|k| a[k].join(&b[k]))),
            (Value::B(a), Value::B(b)) if a == b => Value::B(*a),
            (Value::B(_), Value::B(_)) => Value::B(Tri::Both),
            (a, _) => a.clone(),
        }
    }
}

fn map1<N: Real>(v: Value<N>, f: impl Fn(&N) -> N) -> Value<N> {
    match v {
        Value::F(x) => Value::F(f(&x)),
        Value::T(t) => Value::T(std::array::from_fn(|k| f(&t[k]))),
        b => b,
    }
}

fn map2<N: Real>(a: Value<N>, b: Value<N>, f: impl Fn(&N, &N) -> N) -> Value<N> {
    match (a, b) {
        (Value::F(x), Value::F(y)) => Value::F(f(&x, &y)),
        (a, b) => {
            let (x, y) = (a.triple(), b.triple());
            Value::T(std::array::from_fn(|k| f(&x[k], &y[k])))
        }
    }
}

fn map3<N: Real>(a: Value<N>, b: Value<N>, c: Value<N>, f: impl Fn(&N, &N, &N) -> N) -> Value<N> {
    match (a, b, c) {
        (Value::F(x), Value::F(y), Value::F(z)) => Value::F(f(&x, &y, &z)),
        (a, b, c) => {
            let (x, y, z) = (a.triple(), b.triple(), c.triple());
            Value::T(std::array::from_fn(|k| f(&x[k], &y[k], &z[k])))
        }
    }
}

fn dot<N: Real>(a: &[N; 3], b: &[N; 3]) -> N {
    a[0].mul(&b[0]).add(&a[1].mul(&b[1])).add(&a[2].mul(&b[2]))
}

/// a·a: each component squared (a value times itself is non-negative in every arithmetic).
fn norm2<N: Real>(a: &[N; 3]) -> N {
    a[0].sqr().add(&a[1].sqr()).add(&a[2].sqr())
}

/// `a − b·floor(a/b)` (RenderMan's mod: the result has the sign of b).
pub fn modulo<N: Real>(a: &N, b: &N) -> N {
    a.sub(&b.mul(&a.div(b).floor()))
}

/// Catmull-Rom spline through `knots` (≥ 4) at clamp(t, 0, 1), RenderMan's `spline`: the
/// first and last knots only shape the end tangents. A parameter range that straddles
/// segments is split per segment (interval arithmetic) and the hull taken.
pub fn spline<N: Real>(t: &N, knots: &[N]) -> N {
    spline_at(&spline_parameter(t, knots.len()), knots)
}

/// The spline's segment coordinate clamp(t, 0, 1)·(count − 3) for `count` knots (shared by the
/// channels of a color spline).
pub fn spline_parameter<N: Real>(t: &N, count: usize) -> N {
    let nseg = count - 3;
    t.max(&N::constant(0.0)).min(&N::constant(1.0)).mul(&N::constant(nseg as f64))
}

/// The spline through `knots` at segment coordinate `x` (from [`spline_parameter`]).
pub fn spline_at<N: Real>(x: &N, knots: &[N]) -> N {
    let nseg = knots.len() - 3;
    let seg_of = |v: f64| (v.floor().max(0.0) as usize).min(nseg - 1);
    let b = x.bounds();
    let (s0, s1) = (seg_of(b.lo), seg_of(b.hi));
    if s0 == s1 {
        let local = x.sub(&N::constant(s0 as f64));
        return catmull_rom(s0, &local, knots);
    }
    let kb: Vec<crate::affine::Interval> = knots.iter().map(|k| k.bounds()).collect();
    let mut hull: Option<crate::affine::Interval> = None;
    for s in s0..=s1 {
        let sf = s as f64;
        let lo = b.lo.max(sf);
        let hi = if s == nseg - 1 { b.hi } else { b.hi.min(sf + 1.0) };
        let local =
            crate::affine::Interval::sub(crate::affine::Interval::new(lo, hi), crate::affine::Interval::point(sf));
        let v = catmull_rom(s, &local, &kb);
        hull = Some(hull.map_or(v, |h| h.hull(v)));
    }
    N::from_interval(hull.unwrap_or(crate::affine::Interval::ENTIRE))
}

/// Catmull-Rom segment `s` (knots s..s+3) at local parameter t:
/// ½[2k₁ + (k₂ − k₀)t + (2k₀ − 5k₁ + 4k₂ − k₃)t² + (3k₁ − 3k₂ + k₃ − k₀)t³], in Horner form.
fn catmull_rom<M: Real>(s: usize, t: &M, k: &[M]) -> M {
    let (k0, k1, k2, k3) = (&k[s], &k[s + 1], &k[s + 2], &k[s + 3]);
    let c = |v: f64| M::constant(v);
    let a1 = k2.sub(k0);
    let a2 = k0.mul(&c(2.0)).sub(&k1.mul(&c(5.0))).add(&k2.mul(&c(4.0))).sub(k3);
    let a3 = k1.sub(k2).mul(&c(3.0)).add(k3).sub(k0);
    let poly = a3.mul(t).add(&a2).mul(t).add(&a1).mul(t).add(&k1.mul(&c(2.0)));
    poly.mul(&c(0.5))
}

struct Ctx<'a, N> {
    prog: &'a Checked,
    g: &'a Globals<N>,
    ci: [N; 3],
    /// User-function calls in progress.
    depth: usize,
    /// Interpreter recursion (expressions and statements, across calls).
    level: usize,
    iterations: u64,
    operations: u64,
    /// The innermost call or loop in progress (and the function called), for the messages of
    /// the evaluation budget.
    site: (Pos, Option<usize>),
}

impl<'a, N> Ctx<'a, N> {
    fn new(prog: &'a Checked, g: &'a Globals<N>, ci: [N; 3]) -> Self {
        Ctx { prog, g, ci, depth: 0, level: 0, iterations: 0, operations: 0, site: (Pos { line: 1, col: 1 }, None) }
    }

    /// An error of the evaluation budget at the innermost call or loop in progress.
    #[cold]
    fn over_budget(&self, what: String) -> ShaderError {
        let callee =
            self.site.1.map(|f| format!(" (in a call of '{}')", self.prog.functions[f].name)).unwrap_or_default();
        ShaderError::at(self.site.0, format!("{what}{callee}; see docs/limits.md"))
    }

    /// Counts `n` operations against [`MAX_OPERATIONS`].
    fn count(&mut self, n: u64) -> Result<(), ShaderError> {
        self.operations += n;
        if self.operations > MAX_OPERATIONS {
            return Err(self.budget_error());
        }
        Ok(())
    }

    /// One operation, one level deeper into the interpreter's recursion: checked against
    /// [`MAX_OPERATIONS`] and [`MAX_EVALUATION_DEPTH`] with one branch (this runs for every
    /// node). The caller steps back out with `self.level -= 1`; after an error the evaluation
    /// is abandoned.
    #[inline(always)]
    fn enter(&mut self) -> Result<(), ShaderError> {
        self.operations += 1;
        self.level += 1;
        if self.operations > MAX_OPERATIONS || self.level > MAX_EVALUATION_DEPTH {
            return Err(self.budget_error());
        }
        Ok(())
    }

    /// The error of whichever budget ran out.
    #[cold]
    #[inline(never)]
    fn budget_error(&self) -> ShaderError {
        self.over_budget(if self.operations > MAX_OPERATIONS {
            format!(
                "evaluation budget: more than {MAX_OPERATIONS} operations in one evaluation \
                 (exponential recursion, or loops nested too deep?)"
            )
        } else {
            format!(
                "nesting limit: evaluation nested deeper than {MAX_EVALUATION_DEPTH} levels (recursion through deep expressions)"
            )
        })
    }
}

/// Evaluates the shader for one sample; returns Ci.
pub fn run<N: Real>(prog: &Checked, params: &[Value<f64>], g: &Globals<N>) -> Result<[N; 3], ShaderError> {
    let mut frame: Vec<Value<N>> = vec![Value::F(N::constant(0.0)); prog.slots.max(params.len())];
    for (slot, p) in params.iter().enumerate() {
        frame[slot] = match p {
            Value::F(x) => Value::F(N::constant(*x)),
            Value::T(t) => Value::T(t.map(N::constant)),
            Value::B(b) => Value::B(*b),
        };
    }
    let zero = N::constant(0.0);
    let mut ctx = Ctx::new(prog, g, [zero.clone(), zero.clone(), zero]);
    ctx.stmts(&prog.body, &mut frame)?;
    Ok(ctx.ci)
}

/// Evaluates a constant expression (parameter defaults) with earlier parameters in `frame`.
pub fn eval_const(prog: &Checked, e: &IExpr, frame: &[Value<f64>]) -> Result<Value<f64>, ShaderError> {
    let g = Globals { u: 0.0, v: 0.0, du: 0.0, dv: 0.0, p: [0.0; 3], d: [0.0, 0.0, 1.0] };
    let mut ctx = Ctx::new(prog, &g, [0.0; 3]);
    ctx.expr(e, frame)
}

impl<N: Real> Ctx<'_, N> {
    fn stmts(&mut self, body: &[IStmt], frame: &mut Vec<Value<N>>) -> Result<Option<Value<N>>, ShaderError> {
        for s in body {
            if let Some(r) = self.stmt(s, frame)? {
                return Ok(Some(r));
            }
        }
        Ok(None)
    }

    fn stmt(&mut self, s: &IStmt, frame: &mut Vec<Value<N>>) -> Result<Option<Value<N>>, ShaderError> {
        self.enter()?;
        let r = self.stmt_inner(s, frame);
        self.level -= 1;
        r
    }

    fn stmt_inner(&mut self, s: &IStmt, frame: &mut Vec<Value<N>>) -> Result<Option<Value<N>>, ShaderError> {
        match s {
            IStmt::Assign(slot, e) => {
                let v = self.expr(e, frame)?;
                frame[*slot] = v;
            }
            IStmt::SetCi(e) => {
                self.ci = self.expr(e, frame)?.triple();
            }
            IStmt::Block(b) => return self.stmts(b, frame),
            IStmt::Return(e) => return Ok(Some(self.expr(e, frame)?)),
            IStmt::If(c, a, b) => match self.expr(c, frame)?.tri() {
                Tri::True => return self.stmts(a, frame),
                Tri::False => return self.stmts(b, frame),
                Tri::Both => {
                    // Both branches on copies, then join (returns only occur at a function's end).
                    let mut fa = frame.clone();
                    let ci0 = self.ci.clone();
                    self.stmts(a, &mut fa)?;
                    let ci_a = std::mem::replace(&mut self.ci, ci0);
                    self.stmts(b, frame)?;
                    for (x, y) in frame.iter_mut().zip(&fa) {
                        if *x != *y {
                            *x = y.join(x);
                        }
                    }
                    self.ci = std::array::from_fn(|k| ci_a[k].join(&self.ci[k]));
                }
            },
            IStmt::For { slot, init, cmp, bound, step, body, pos } => {
                let start = self.constant(init, frame, *pos)?;
                let end = self.constant(bound, frame, *pos)?;
                let inc = self.constant(step, frame, *pos)?;
                let go = |i: f64| match cmp {
                    CmpOp::Lt => i < end,
                    CmpOp::Le => i <= end,
                    CmpOp::Gt => i > end,
                    _ => i >= end,
                };
                let loop_limit = || {
                    ShaderError::at(
                        *pos,
                        format!("loop limit: more than {MAX_LOOP_ITERATIONS} loop iterations in one evaluation (check the loop's bounds and step)"),
                    )
                };
                // The bounds are constants: a loop that would run past the limit (or for ever:
                // a step of 0 or the wrong sign) is refused before its first iteration.
                // A step that does not move i towards the bound (0, the wrong sign, or NaN).
                let forever =
                    end != start && (inc * (end - start)).partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater);
                if go(start) && (forever || (end - start) / inc > MAX_LOOP_ITERATIONS as f64) {
                    return Err(loop_limit());
                }
                let outer = std::mem::replace(&mut self.site, (*pos, None));
                let mut i = start;
                loop {
                    if !go(i) {
                        break;
                    }
                    self.iterations += 1;
                    if self.iterations > MAX_LOOP_ITERATIONS || !i.is_finite() {
                        return Err(loop_limit());
                    }
                    frame[*slot] = Value::F(N::constant(i));
                    if let Some(r) = self.stmts(body, frame)? {
                        self.site = outer;
                        return Ok(Some(r));
                    }
                    i += inc;
                }
                self.site = outer;
            }
        }
        Ok(None)
    }

    /// A loop bound: constant by the checker's rule, so exactly known in every arithmetic.
    fn constant(&mut self, e: &IExpr, frame: &[Value<N>], pos: Pos) -> Result<f64, ShaderError> {
        self.expr(e, frame)?.float().as_constant().ok_or_else(|| ShaderError::at(pos, "loop bounds must be constant"))
    }

    fn expr(&mut self, e: &IExpr, frame: &[Value<N>]) -> Result<Value<N>, ShaderError> {
        self.enter()?;
        let v = self.expr_inner(e, frame);
        self.level -= 1;
        v
    }

    /// One expression: a dispatch to one small method per kind of node, none inlined here, so
    /// that each level of nesting costs the stack of [`Ctx::expr`], this dispatch and one of
    /// them — about 1 KiB with affine numbers, measured (`docs/limits.md`), where one
    /// function with every case inline took 8 KiB.
    fn expr_inner(&mut self, e: &IExpr, frame: &[Value<N>]) -> Result<Value<N>, ShaderError> {
        match e {
            IExpr::Const(x) => Ok(Value::F(N::constant(*x))),
            IExpr::Local(s) => Ok(frame[*s].clone()),
            IExpr::Global(g) => Ok(self.global(*g)),
            IExpr::Neg(a) => self.unary(a, frame, negate),
            IExpr::Arith(ArOp::Mul, a, b) if a == b && matches!(**a, IExpr::Local(_) | IExpr::Global(_)) => {
                // The same variable twice: a square, not a product of independent values.
                self.unary(a, frame, square)
            }
            IExpr::Arith(op, a, b) => self.binary(a, b, frame, |x, y| arith(*op, x, y)),
            IExpr::Cmp(op, a, b) => self.binary(a, b, frame, |x, y| Value::B(compare(*op, &x.float(), &y.float()))),
            IExpr::And(a, b) => self.binary(a, b, frame, |x, y| Value::B(x.tri().and(y.tri()))),
            IExpr::Or(a, b) => self.binary(a, b, frame, |x, y| Value::B(x.tri().or(y.tri()))),
            IExpr::Not(a) => self.unary(a, frame, |x| Value::B(x.tri().not())),
            IExpr::Select(c, a, b) => self.select(c, a, b, frame),
            IExpr::Construct(args) => self.construct(args, frame),
            IExpr::Component(a, k) => self.unary(a, frame, |v| component(v, *k)),
            IExpr::User(fi, args, pos) => self.call(*fi, args, *pos, frame),
            IExpr::Builtin(b, args) => self.builtin(*b, args, frame),
        }
    }

    #[inline(never)]
    fn unary(
        &mut self,
        a: &IExpr,
        frame: &[Value<N>],
        f: impl FnOnce(Value<N>) -> Value<N>,
    ) -> Result<Value<N>, ShaderError> {
        Ok(f(self.expr(a, frame)?))
    }

    #[inline(never)]
    fn binary(
        &mut self,
        a: &IExpr,
        b: &IExpr,
        frame: &[Value<N>],
        f: impl FnOnce(Value<N>, Value<N>) -> Value<N>,
    ) -> Result<Value<N>, ShaderError> {
        let a = self.expr(a, frame)?;
        Ok(f(a, self.expr(b, frame)?))
    }

    /// A triple from one (broadcast) or three floats, without a vector of the values (colours
    /// are built in every evaluation).
    #[inline(never)]
    fn construct(&mut self, args: &[IExpr], frame: &[Value<N>]) -> Result<Value<N>, ShaderError> {
        if let [a] = args {
            return Ok(Value::T(self.expr(a, frame)?.triple()));
        }
        let x = self.expr(&args[0], frame)?.float();
        let y = self.expr(&args[1], frame)?.float();
        let z = self.expr(&args[2], frame)?.float();
        Ok(Value::T([x, y, z]))
    }

    #[inline(never)]
    fn select(&mut self, c: &IExpr, a: &IExpr, b: &IExpr, frame: &[Value<N>]) -> Result<Value<N>, ShaderError> {
        match self.expr(c, frame)?.tri() {
            Tri::True => self.expr(a, frame),
            Tri::False => self.expr(b, frame),
            Tri::Both => self.binary(a, b, frame, |x, y| x.join(&y)),
        }
    }

    #[inline(never)]
    fn builtin(&mut self, b: Builtin, args: &[IExpr], frame: &[Value<N>]) -> Result<Value<N>, ShaderError> {
        let values = self.args(args, frame)?;
        self.count(builtin_cost(b, &values))?;
        Ok(apply_builtin(b, values))
    }

    fn global(&self, g: Global) -> Value<N> {
        match g {
            Global::U => Value::F(self.g.u.clone()),
            Global::V => Value::F(self.g.v.clone()),
            Global::Du => Value::F(self.g.du.clone()),
            Global::Dv => Value::F(self.g.dv.clone()),
            Global::P => Value::T(self.g.p.clone()),
            Global::D => Value::T(self.g.d.clone()),
            Global::Ci => Value::T(self.ci.clone()),
        }
    }

    /// The values of `args`, in order.
    #[inline(never)]
    fn args(&mut self, args: &[IExpr], frame: &[Value<N>]) -> Result<Vec<Value<N>>, ShaderError> {
        let mut v = Vec::with_capacity(args.len());
        for a in args {
            v.push(self.expr(a, frame)?);
        }
        Ok(v)
    }

    /// A user-function call at `pos`.
    #[inline(never)]
    fn call(&mut self, fi: usize, args: &[IExpr], pos: Pos, frame: &[Value<N>]) -> Result<Value<N>, ShaderError> {
        let f = &self.prog.functions[fi];
        if self.depth >= MAX_CALL_DEPTH {
            return Err(ShaderError::at(
                pos,
                format!("recursion limit: calls nested deeper than {MAX_CALL_DEPTH} (in '{}')", f.name),
            ));
        }
        let mut callee = self.args(args, frame)?;
        callee.resize(f.slots.max(args.len()), Value::F(N::constant(0.0)));
        self.depth += 1;
        let outer = std::mem::replace(&mut self.site, (pos, Some(fi)));
        let r = self.stmts(&f.body, &mut callee);
        self.site = outer;
        self.depth -= 1;
        Ok(r?.unwrap_or(Value::F(N::constant(0.0))))
    }
}

#[inline(never)]
fn negate<N: Real>(v: Value<N>) -> Value<N> {
    map1(v, |x| x.neg())
}

#[inline(never)]
fn square<N: Real>(v: Value<N>) -> Value<N> {
    map1(v, |x| x.sqr())
}

#[inline(never)]
fn arith<N: Real>(op: ArOp, a: Value<N>, b: Value<N>) -> Value<N> {
    match op {
        ArOp::Add => map2(a, b, |x, y| x.add(y)),
        ArOp::Sub => map2(a, b, |x, y| x.sub(y)),
        ArOp::Mul => map2(a, b, |x, y| x.mul(y)),
        ArOp::Div => map2(a, b, |x, y| x.div(y)),
    }
}

#[inline(never)]
fn component<N: Real>(v: Value<N>, k: usize) -> Value<N> {
    let t = v.triple();
    Value::F(t[k].clone())
}

/// What a builtin counts against [`MAX_OPERATIONS`]: 1, or [`NOISE_OPERATIONS`] per noise
/// evaluation (one per octave of fbm and turbulence).
fn builtin_cost<N: Real>(b: Builtin, args: &[Value<N>]) -> u64 {
    match b {
        Builtin::Noise | Builtin::Snoise => NOISE_OPERATIONS,
        Builtin::Fbm | Builtin::Turbulence => NOISE_OPERATIONS * octave_count(args) as u64,
        _ => 1,
    }
}

/// The octave count of fbm/turbulence (a constant by the checker's rule), clamped to
/// 1..=[`MAX_OCTAVES`].
fn octave_count<N: Real>(args: &[Value<N>]) -> usize {
    let octaves = args.get(1).and_then(|o| o.clone().float().as_constant()).unwrap_or(6.0);
    if octaves.is_nan() {
        return 1;
    }
    (octaves.round().max(1.0) as usize).min(MAX_OCTAVES)
}

/// A builtin applied to its argument values.
#[inline(never)]
fn apply_builtin<N: Real>(b: Builtin, v: Vec<Value<N>>) -> Value<N> {
    use Builtin::*;
    let nargs = v.len();
    let octaves = octave_count(&v);
    let mut it = v.into_iter();
    let mut next = || it.next().unwrap_or(Value::F(N::constant(0.0)));
    let c = |x: f64| N::constant(x);
    match b {
        Sin => map1(next(), |x| x.sin()),
        Cos => map1(next(), |x| x.cos()),
        Sqrt => map1(next(), |x| x.sqrt()),
        Exp => map1(next(), |x| x.exp()),
        Log => map1(next(), |x| x.ln()),
        Abs => map1(next(), |x| x.abs()),
        Floor => map1(next(), |x| x.floor()),
        Ceil => map1(next(), |x| x.neg().floor().neg()),
        Fract => map1(next(), |x| x.sub(&x.floor())),
        Pow => map2(next(), next(), |x, y| x.pow(y)),
        Min => map2(next(), next(), |x, y| x.min(y)),
        Max => map2(next(), next(), |x, y| x.max(y)),
        Mod => map2(next(), next(), modulo),
        Step => map2(next(), next(), |edge, x| x.sub(edge).step0()),
        Clamp => map3(next(), next(), next(), |x, lo, hi| x.max(lo).min(hi)),
        Mix => map3(next(), next(), next(), |a, b, t| a.add(&b.sub(a).mul(t))),
        Smoothstep => map3(next(), next(), next(), |e0, e1, x| x.sub(e0).div(&e1.sub(e0)).smooth01()),
        Noise | Snoise => {
            let (dim, p) = match nargs {
                2 => (2, [next().float(), next().float(), c(0.0)]),
                _ => match next() {
                    Value::T(t) => (3, t),
                    other => (1, [other.float(), c(0.0), c(0.0)]),
                },
            };
            let n = noise::snoise(dim, &p);
            Value::F(if b == Noise { n.mul(&c(0.5)).add(&c(0.5)) } else { n })
        }
        Fbm | Turbulence => {
            let p = next().triple();
            if nargs > 1 {
                next(); // the octave count, read by octave_count
            }
            let lac = if nargs > 2 { next().float() } else { c(2.0) };
            let gain = if nargs > 3 { next().float() } else { c(0.5) };
            Value::F(noise::fbm(&p, octaves, &lac, &gain, b == Turbulence))
        }
        Spline => {
            let t = next().float();
            let knots: Vec<Value<N>> = (1..nargs).map(|_| next()).collect();
            match knots.first() {
                Some(Value::T(_)) => {
                    let ks: Vec<[N; 3]> = knots.into_iter().map(|k| k.triple()).collect();
                    let x = spline_parameter(&t, ks.len());
                    Value::T(std::array::from_fn(|ch| {
                        let kc: Vec<N> = ks.iter().map(|k| k[ch].clone()).collect();
                        spline_at(&x, &kc)
                    }))
                }
                _ => {
                    let kc: Vec<N> = knots.into_iter().map(|k| k.float()).collect();
                    Value::F(spline(&t, &kc))
                }
            }
        }
        Length => {
            let a = next().triple();
            Value::F(norm2(&a).sqrt())
        }
        Dot => Value::F(dot(&next().triple(), &next().triple())),
        Distance => {
            let (a, b) = (next().triple(), next().triple());
            let d: [N; 3] = std::array::from_fn(|k| a[k].sub(&b[k]));
            Value::F(norm2(&d).sqrt())
        }
        Normalize => {
            let a = next().triple();
            let len = norm2(&a).sqrt();
            Value::T(std::array::from_fn(|k| a[k].div(&len)))
        }
        Cross => {
            let (a, b) = (next().triple(), next().triple());
            Value::T([
                a[1].mul(&b[2]).sub(&a[2].mul(&b[1])),
                a[2].mul(&b[0]).sub(&a[0].mul(&b[2])),
                a[0].mul(&b[1]).sub(&a[1].mul(&b[0])),
            ])
        }
        Xcomp => Value::F(next().triple()[0].clone()),
        Ycomp => Value::F(next().triple()[1].clone()),
        Zcomp => Value::F(next().triple()[2].clone()),
        Luminance => {
            let a = next().triple();
            Value::F(a[0].mul(&c(0.2126)).add(&a[1].mul(&c(0.7152))).add(&a[2].mul(&c(0.0722))))
        }
    }
}

/// Three-valued comparison through the sign of a difference (for `f64` exactly `a < b` etc.:
/// IEEE subtraction is exact in sign).
fn compare<N: Real>(op: CmpOp, a: &N, b: &N) -> Tri {
    let lt = |x: &N, y: &N| match x.sub(y).sign() {
        Sign::Negative => Tri::True,
        Sign::NonNegative => Tri::False,
        Sign::Both => Tri::Both,
    };
    match op {
        CmpOp::Lt => lt(a, b),
        CmpOp::Ge => lt(a, b).not(),
        CmpOp::Gt => lt(b, a),
        CmpOp::Le => lt(b, a).not(),
        CmpOp::Eq | CmpOp::Ne => {
            let d = a.sub(b);
            let eq = match d.as_constant() {
                Some(x) => {
                    if x == 0.0 {
                        Tri::True
                    } else {
                        Tri::False
                    }
                }
                None => {
                    if d.bounds().contains(0.0) {
                        Tri::Both
                    } else {
                        Tri::False
                    }
                }
            };
            if op == CmpOp::Eq {
                eq
            } else {
                eq.not()
            }
        }
    }
}
