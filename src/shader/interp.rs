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

/// Deepest user-function call chain (recursion limit).
pub const MAX_CALL_DEPTH: usize = 64;
/// Most loop iterations in one evaluation of the shader.
pub const MAX_LOOP_ITERATIONS: u64 = 1_000_000;
/// Most octaves of fbm/turbulence (larger counts are clamped).
pub const MAX_OCTAVES: usize = 16;

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
    depth: usize,
    iterations: u64,
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
    let mut ctx = Ctx { prog, g, ci: [zero.clone(), zero.clone(), zero], depth: 0, iterations: 0 };
    ctx.stmts(&prog.body, &mut frame)?;
    Ok(ctx.ci)
}

/// Evaluates a constant expression (parameter defaults) with earlier parameters in `frame`.
pub fn eval_const(prog: &Checked, e: &IExpr, frame: &[Value<f64>]) -> Result<Value<f64>, ShaderError> {
    let g = Globals { u: 0.0, v: 0.0, du: 0.0, dv: 0.0, p: [0.0; 3], d: [0.0, 0.0, 1.0] };
    let mut ctx = Ctx { prog, g: &g, ci: [0.0; 3], depth: 0, iterations: 0 };
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
                let mut i = start;
                loop {
                    let go = match cmp {
                        CmpOp::Lt => i < end,
                        CmpOp::Le => i <= end,
                        CmpOp::Gt => i > end,
                        _ => i >= end,
                    };
                    if !go {
                        break;
                    }
                    self.iterations += 1;
                    if self.iterations > MAX_LOOP_ITERATIONS || !i.is_finite() {
                        return Err(ShaderError::at(
                            *pos,
                            format!("loop limit: more than {MAX_LOOP_ITERATIONS} loop iterations in one evaluation (check the loop's bounds and step)"),
                        ));
                    }
                    frame[*slot] = Value::F(N::constant(i));
                    if let Some(r) = self.stmts(body, frame)? {
                        return Ok(Some(r));
                    }
                    i += inc;
                }
            }
        }
        Ok(None)
    }

    /// A loop bound: constant by the checker's rule, so exactly known in every arithmetic.
    fn constant(&mut self, e: &IExpr, frame: &[Value<N>], pos: Pos) -> Result<f64, ShaderError> {
        self.expr(e, frame)?.float().as_constant().ok_or_else(|| ShaderError::at(pos, "loop bounds must be constant"))
    }

    fn expr(&mut self, e: &IExpr, frame: &[Value<N>]) -> Result<Value<N>, ShaderError> {
        Ok(match e {
            IExpr::Const(x) => Value::F(N::constant(*x)),
            IExpr::Local(s) => frame[*s].clone(),
            IExpr::Global(g) => match g {
                Global::U => Value::F(self.g.u.clone()),
                Global::V => Value::F(self.g.v.clone()),
                Global::Du => Value::F(self.g.du.clone()),
                Global::Dv => Value::F(self.g.dv.clone()),
                Global::P => Value::T(self.g.p.clone()),
                Global::D => Value::T(self.g.d.clone()),
                Global::Ci => Value::T(self.ci.clone()),
            },
            IExpr::Neg(a) => map1(self.expr(a, frame)?, |x| x.neg()),
            IExpr::Arith(ArOp::Mul, a, b) if a == b && matches!(**a, IExpr::Local(_) | IExpr::Global(_)) => {
                // The same variable twice: a square, not a product of independent values.
                map1(self.expr(a, frame)?, |x| x.sqr())
            }
            IExpr::Arith(op, a, b) => {
                let (a, b) = (self.expr(a, frame)?, self.expr(b, frame)?);
                match op {
                    ArOp::Add => map2(a, b, |x, y| x.add(y)),
                    ArOp::Sub => map2(a, b, |x, y| x.sub(y)),
                    ArOp::Mul => map2(a, b, |x, y| x.mul(y)),
                    ArOp::Div => map2(a, b, |x, y| x.div(y)),
                }
            }
            IExpr::Cmp(op, a, b) => {
                let (a, b) = (self.expr(a, frame)?.float(), self.expr(b, frame)?.float());
                Value::B(compare(*op, &a, &b))
            }
            IExpr::And(a, b) => Value::B(self.expr(a, frame)?.tri().and(self.expr(b, frame)?.tri())),
            IExpr::Or(a, b) => Value::B(self.expr(a, frame)?.tri().or(self.expr(b, frame)?.tri())),
            IExpr::Not(a) => Value::B(self.expr(a, frame)?.tri().not()),
            IExpr::Select(c, a, b) => match self.expr(c, frame)?.tri() {
                Tri::True => self.expr(a, frame)?,
                Tri::False => self.expr(b, frame)?,
                Tri::Both => self.expr(a, frame)?.join(&self.expr(b, frame)?),
            },
            IExpr::Construct(args) => {
                if args.len() == 1 {
                    Value::T(self.expr(&args[0], frame)?.triple())
                } else {
                    let x = self.expr(&args[0], frame)?.float();
                    let y = self.expr(&args[1], frame)?.float();
                    let z = self.expr(&args[2], frame)?.float();
                    Value::T([x, y, z])
                }
            }
            IExpr::Component(a, k) => {
                let t = self.expr(a, frame)?.triple();
                Value::F(t[*k].clone())
            }
            IExpr::User(fi, args, pos) => {
                let f = &self.prog.functions[*fi];
                if self.depth >= MAX_CALL_DEPTH {
                    return Err(ShaderError::at(
                        *pos,
                        format!("recursion limit: calls nested deeper than {MAX_CALL_DEPTH} (in '{}')", f.name),
                    ));
                }
                let mut callee: Vec<Value<N>> = vec![Value::F(N::constant(0.0)); f.slots.max(args.len())];
                for (k, a) in args.iter().enumerate() {
                    callee[k] = self.expr(a, frame)?;
                }
                self.depth += 1;
                let r = self.stmts(&f.body, &mut callee);
                self.depth -= 1;
                r?.unwrap_or(Value::F(N::constant(0.0)))
            }
            IExpr::Builtin(b, args) => self.builtin(*b, args, frame)?,
        })
    }

    fn builtin(&mut self, b: Builtin, args: &[IExpr], frame: &[Value<N>]) -> Result<Value<N>, ShaderError> {
        use Builtin::*;
        let mut v = Vec::with_capacity(args.len());
        for a in args {
            v.push(self.expr(a, frame)?);
        }
        let mut it = v.into_iter();
        let mut next = || it.next().unwrap_or(Value::F(N::constant(0.0)));
        let c = |x: f64| N::constant(x);
        Ok(match b {
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
                let (dim, p) = match args.len() {
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
                let octaves = if args.len() > 1 { next().float().as_constant().unwrap_or(6.0) } else { 6.0 };
                let octaves = (octaves.round().max(1.0) as usize).min(MAX_OCTAVES);
                let lac = if args.len() > 2 { next().float() } else { c(2.0) };
                let gain = if args.len() > 3 { next().float() } else { c(0.5) };
                Value::F(noise::fbm(&p, octaves, &lac, &gain, b == Turbulence))
            }
            Spline => {
                let t = next().float();
                let knots: Vec<Value<N>> = (1..args.len()).map(|_| next()).collect();
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
        })
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
