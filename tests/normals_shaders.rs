//! The emitted shader decoders parse and validate (naga's WGSL and GLSL front ends + validator)
//! for every scheme at budgets that exercise one-word, straddling and two-word layouts, and they
//! decode like the Rust decoder: a small interpreter of naga's IR runs the parsed WGSL and GLSL
//! (the very modules a GPU driver would compile) in f32 and compares the directions. The HLSL
//! output shares its text with the GLSL apart from type names; glslang compiles it
//! (`tests/hlsl_snippets.rs`).

use glam::DVec3;
use naga::{BinaryOperator as Bin, Expression as E, Handle, Literal, MathFunction as M, ScalarKind, Statement};
use prtkit::normals::metrics::angle_between;
use prtkit::normals::shader::{decoder, Language};
use prtkit::normals::{Codec, Scheme};
use prtkit::rng::SplitMix64;
use std::collections::HashMap;

const BUDGETS: [u32; 8] = [8, 16, 19, 31, 32, 33, 48, 64];

fn validate(module: &naga::Module, what: &str) {
    let mut v = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all());
    if let Err(e) = v.validate(module) {
        panic!("{what}: invalid module: {e:?}");
    }
}

fn wgsl_module(codec: &Codec) -> naga::Module {
    let mut src = decoder(codec, Language::Wgsl);
    // An entry point that uses the function, so nothing is dead code.
    src += if codec.bits() <= 32 {
        "@fragment fn main(@location(0) @interpolate(flat) c: u32) -> @location(0) vec4<f32> { return vec4<f32>(prtkit_decode_normal(c), 1.0); }\n"
    } else {
        "@fragment fn main(@location(0) @interpolate(flat) c: vec2<u32>) -> @location(0) vec4<f32> { return vec4<f32>(prtkit_decode_normal(c.x, c.y), 1.0); }\n"
    };
    let module =
        naga::front::wgsl::parse_str(&src).unwrap_or_else(|e| panic!("{codec:?}: {}\n{src}", e.emit_to_string(&src)));
    validate(&module, &format!("wgsl {codec:?}"));
    module
}

fn glsl_module(codec: &Codec) -> naga::Module {
    let mut src = String::from("#version 450\n");
    src += &decoder(codec, Language::Glsl);
    src += if codec.bits() <= 32 {
        "layout(location = 0) flat in uint c;\nlayout(location = 0) out vec4 o;\nvoid main() { o = vec4(prtkit_decode_normal(c), 1.0); }\n"
    } else {
        "layout(location = 0) flat in uvec2 c;\nlayout(location = 0) out vec4 o;\nvoid main() { o = vec4(prtkit_decode_normal(c.x, c.y), 1.0); }\n"
    };
    let mut frontend = naga::front::glsl::Frontend::default();
    let options = naga::front::glsl::Options::from(naga::ShaderStage::Fragment);
    let module = frontend.parse(&options, &src).unwrap_or_else(|e| panic!("{codec:?}: {e:?}\n{src}"));
    validate(&module, &format!("glsl {codec:?}"));
    module
}

#[test]
fn wgsl_decoders_validate() {
    for scheme in Scheme::ALL {
        for bits in BUDGETS {
            wgsl_module(&Codec::new(scheme, bits).unwrap());
        }
    }
}

#[test]
fn glsl_decoders_validate() {
    for scheme in Scheme::ALL {
        for bits in BUDGETS {
            glsl_module(&Codec::new(scheme, bits).unwrap());
        }
    }
}

/// A scalar of the shading languages' 32-bit types.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Scalar {
    F(f32),
    U(u32),
    I(i32),
    B(bool),
}

/// A value: scalar, vector, or a pointer to a local variable (with a component for `v.x = …`).
#[derive(Clone, Debug, PartialEq)]
enum Value {
    S(Scalar),
    V(Vec<Scalar>),
    Ptr(Handle<naga::LocalVariable>, Option<usize>),
}

impl Value {
    fn scalars(&self) -> Vec<Scalar> {
        match self {
            Value::S(s) => vec![*s],
            Value::V(v) => v.clone(),
            Value::Ptr(..) => panic!("pointer used as a value"),
        }
    }
    /// Applies `f` lane by lane, broadcasting a scalar against a vector.
    fn zip(&self, other: &Value, f: impl Fn(Scalar, Scalar) -> Scalar) -> Value {
        match (self, other) {
            (Value::S(a), Value::S(b)) => Value::S(f(*a, *b)),
            _ => {
                let (a, b) = (self.scalars(), other.scalars());
                let n = a.len().max(b.len());
                Value::V((0..n).map(|i| f(a[i.min(a.len() - 1)], b[i.min(b.len() - 1)])).collect())
            }
        }
    }
    fn map(&self, f: impl Fn(Scalar) -> Scalar) -> Value {
        match self {
            Value::S(a) => Value::S(f(*a)),
            _ => Value::V(self.scalars().into_iter().map(f).collect()),
        }
    }
}

fn float(s: Scalar) -> f32 {
    match s {
        Scalar::F(x) => x,
        other => panic!("expected a float, got {other:?}"),
    }
}

enum Flow {
    Next,
    Break,
    Continue,
    Return(Option<Value>),
}

/// Runs one function of a module: expressions are evaluated when emitted (so a `Load` sees the
/// variable as it is at that point), statements in order.
struct Frame<'a> {
    module: &'a naga::Module,
    function: &'a naga::Function,
    args: Vec<Value>,
    locals: HashMap<Handle<naga::LocalVariable>, Value>,
    values: HashMap<Handle<naga::Expression>, Value>,
}

fn call(module: &naga::Module, function: &naga::Function, args: Vec<Value>) -> Value {
    call_with_names(module, function, args).0
}

/// Runs `function` and also returns the final value of every named binding (WGSL `let`, GLSL
/// local variable), so tests can check intermediate integers such as the decoded digits.
fn call_with_names(
    module: &naga::Module,
    function: &naga::Function,
    args: Vec<Value>,
) -> (Value, HashMap<String, Value>) {
    let mut frame = Frame { module, function, args, locals: HashMap::new(), values: HashMap::new() };
    for (h, local) in function.local_variables.iter() {
        if let Some(init) = local.init {
            let v = frame.eval(init);
            frame.locals.insert(h, v);
        }
    }
    let result = match frame.block(&function.body) {
        Flow::Return(Some(v)) => v,
        _ => panic!("{:?} returned nothing", function.name),
    };
    let mut names: HashMap<String, Value> = function
        .named_expressions
        .iter()
        .filter_map(|(h, name)| frame.values.get(h).map(|v| (name.clone(), v.clone())))
        .collect();
    for (h, local) in function.local_variables.iter() {
        if let (Some(name), Some(v)) = (&local.name, frame.locals.get(&h)) {
            names.insert(name.clone(), v.clone());
        }
    }
    (result, names)
}

fn literal(l: &Literal) -> Value {
    Value::S(match *l {
        Literal::F32(x) => Scalar::F(x),
        Literal::U32(x) => Scalar::U(x),
        Literal::I32(x) => Scalar::I(x),
        Literal::Bool(x) => Scalar::B(x),
        Literal::AbstractInt(x) => Scalar::I(x as i32),
        Literal::AbstractFloat(x) => Scalar::F(x as f32),
        ref other => panic!("unsupported literal {other:?}"),
    })
}

/// Constants live in the module's global expressions: literals and compositions of them.
fn global(module: &naga::Module, h: Handle<naga::Expression>) -> Value {
    match &module.global_expressions[h] {
        E::Literal(l) => literal(l),
        E::Constant(c) => global(module, module.constants[*c].init),
        E::Compose { components, .. } => {
            Value::V(components.iter().flat_map(|c| global(module, *c).scalars()).collect())
        }
        other => panic!("unsupported constant expression {other:?}"),
    }
}

fn binary(op: Bin, a: Scalar, b: Scalar) -> Scalar {
    use Scalar::*;
    match (op, a, b) {
        (Bin::Add, F(x), F(y)) => F(x + y),
        (Bin::Subtract, F(x), F(y)) => F(x - y),
        (Bin::Multiply, F(x), F(y)) => F(x * y),
        (Bin::Divide, F(x), F(y)) => F(x / y),
        (Bin::Add, U(x), U(y)) => U(x.wrapping_add(y)),
        (Bin::Subtract, U(x), U(y)) => U(x.wrapping_sub(y)),
        (Bin::Multiply, U(x), U(y)) => U(x.wrapping_mul(y)),
        (Bin::Divide, U(x), U(y)) => U(x / y),
        (Bin::Modulo, U(x), U(y)) => U(x % y),
        (Bin::Subtract, I(x), I(y)) => I(x.wrapping_sub(y)),
        (Bin::And, U(x), U(y)) => U(x & y),
        (Bin::InclusiveOr, U(x), U(y)) => U(x | y),
        (Bin::ShiftLeft, U(x), U(y)) => U(x.wrapping_shl(y)),
        (Bin::ShiftRight, U(x), U(y)) => U(x.wrapping_shr(y)),
        (Bin::ShiftRight, I(x), U(y)) => I(x.wrapping_shr(y)),
        (Bin::ShiftRight, I(x), I(y)) => I(x.wrapping_shr(y as u32)),
        (Bin::LogicalOr, B(x), B(y)) => B(x || y),
        (Bin::LogicalAnd, B(x), B(y)) => B(x && y),
        (Bin::Equal, x, y) => B(x == y),
        (Bin::NotEqual, x, y) => B(x != y),
        (Bin::Less, F(x), F(y)) => B(x < y),
        (Bin::GreaterEqual, F(x), F(y)) => B(x >= y),
        (Bin::Less, U(x), U(y)) => B(x < y),
        (Bin::GreaterEqual, U(x), U(y)) => B(x >= y),
        _ => panic!("unsupported {op:?} on {a:?}, {b:?}"),
    }
}

fn convert(s: Scalar, kind: ScalarKind, bitcast: bool) -> Scalar {
    use Scalar::*;
    match (s, kind, bitcast) {
        (U(x), ScalarKind::Sint, _) => I(x as i32),
        (I(x), ScalarKind::Uint, _) => U(x as u32),
        (U(x), ScalarKind::Float, false) => F(x as f32),
        (I(x), ScalarKind::Float, false) => F(x as f32),
        (x @ U(_), ScalarKind::Uint, _) | (x @ I(_), ScalarKind::Sint, _) | (x @ F(_), ScalarKind::Float, _) => x,
        _ => panic!("unsupported conversion of {s:?} to {kind:?}"),
    }
}

fn math(fun: M, a: &Value, b: Option<Value>) -> Value {
    let f1 = |f: fn(f32) -> f32| a.map(|s| Scalar::F(f(float(s))));
    match fun {
        M::Abs => f1(f32::abs),
        M::Sqrt => f1(f32::sqrt),
        M::Sin => f1(f32::sin),
        M::Cos => f1(f32::cos),
        M::Max => a.zip(&b.expect("max takes two arguments"), |x, y| match (x, y) {
            (Scalar::F(x), Scalar::F(y)) => Scalar::F(x.max(y)),
            (Scalar::U(x), Scalar::U(y)) => Scalar::U(x.max(y)),
            _ => panic!("max of {x:?}, {y:?}"),
        }),
        M::Min => a.zip(&b.expect("min takes two arguments"), |x, y| match (x, y) {
            (Scalar::F(x), Scalar::F(y)) => Scalar::F(x.min(y)),
            (Scalar::U(x), Scalar::U(y)) => Scalar::U(x.min(y)),
            _ => panic!("min of {x:?}, {y:?}"),
        }),
        M::Normalize => {
            let v: Vec<f32> = a.scalars().into_iter().map(float).collect();
            let length = v.iter().map(|x| x * x).sum::<f32>().sqrt();
            Value::V(v.into_iter().map(|x| Scalar::F(x / length)).collect())
        }
        other => panic!("unsupported math function {other:?}"),
    }
}

impl Frame<'_> {
    fn eval(&mut self, h: Handle<naga::Expression>) -> Value {
        if let Some(v) = self.values.get(&h) {
            return v.clone();
        }
        let v = match &self.function.expressions[h] {
            E::Literal(l) => literal(l),
            E::Constant(c) => global(self.module, self.module.constants[*c].init),
            E::FunctionArgument(i) => self.args[*i as usize].clone(),
            E::LocalVariable(lv) => Value::Ptr(*lv, None),
            E::Load { pointer } => match self.eval(*pointer) {
                Value::Ptr(lv, None) => self.locals[&lv].clone(),
                Value::Ptr(lv, Some(i)) => Value::S(self.locals[&lv].scalars()[i]),
                other => panic!("load from {other:?}"),
            },
            E::Compose { components, .. } => {
                Value::V(components.iter().flat_map(|c| self.eval(*c).scalars()).collect())
            }
            E::Splat { size, value } => Value::V(vec![self.eval(*value).scalars()[0]; *size as usize]),
            E::Swizzle { size, vector, pattern } => {
                let v = self.eval(*vector).scalars();
                Value::V(pattern[..*size as usize].iter().map(|&c| v[c as usize]).collect())
            }
            E::AccessIndex { base, index } => match self.eval(*base) {
                Value::Ptr(lv, None) => Value::Ptr(lv, Some(*index as usize)),
                v => Value::S(v.scalars()[*index as usize]),
            },
            E::Unary { op, expr } => {
                let op = *op;
                self.eval(*expr).map(|s| match (op, s) {
                    (naga::UnaryOperator::Negate, Scalar::F(x)) => Scalar::F(-x),
                    (naga::UnaryOperator::Negate, Scalar::I(x)) => Scalar::I(x.wrapping_neg()),
                    (naga::UnaryOperator::LogicalNot, Scalar::B(x)) => Scalar::B(!x),
                    _ => panic!("unsupported {op:?} on {s:?}"),
                })
            }
            E::Binary { op, left, right } => {
                let (op, a, b) = (*op, self.eval(*left), self.eval(*right));
                a.zip(&b, |x, y| binary(op, x, y))
            }
            E::Select { condition, accept, reject } => {
                let (c, a, r) = (self.eval(*condition), self.eval(*accept), self.eval(*reject));
                match c {
                    Value::S(Scalar::B(true)) => a,
                    Value::S(Scalar::B(false)) => r,
                    other => panic!("select on {other:?}"),
                }
            }
            E::Math { fun, arg, arg1, .. } => {
                let a = self.eval(*arg);
                let b = arg1.map(|h| self.eval(h));
                math(*fun, &a, b)
            }
            E::As { expr, kind, convert: width } => {
                let (kind, bitcast) = (*kind, width.is_none());
                self.eval(*expr).map(|s| convert(s, kind, bitcast))
            }
            E::CallResult(_) => panic!("call result read before the call"),
            other => panic!("unsupported expression {other:?}"),
        };
        v
    }

    fn block(&mut self, block: &naga::Block) -> Flow {
        for statement in block.iter() {
            match statement {
                Statement::Emit(range) => {
                    for h in range.clone() {
                        self.values.remove(&h);
                        let v = self.eval(h);
                        self.values.insert(h, v);
                    }
                }
                Statement::Block(b) => match self.block(b) {
                    Flow::Next => {}
                    flow => return flow,
                },
                Statement::If { condition, accept, reject } => {
                    let taken = if self.eval(*condition) == Value::S(Scalar::B(true)) { accept } else { reject };
                    match self.block(taken) {
                        Flow::Next => {}
                        flow => return flow,
                    }
                }
                Statement::Loop { body, continuing, break_if } => loop {
                    match self.block(body) {
                        Flow::Break => break,
                        Flow::Return(v) => return Flow::Return(v),
                        Flow::Next | Flow::Continue => {}
                    }
                    self.block(continuing);
                    if let Some(b) = break_if {
                        if self.eval(*b) == Value::S(Scalar::B(true)) {
                            break;
                        }
                    }
                },
                Statement::Break => return Flow::Break,
                Statement::Continue => return Flow::Continue,
                Statement::Return { value } => return Flow::Return(value.map(|h| self.eval(h))),
                Statement::Store { pointer, value } => {
                    let v = self.eval(*value);
                    match self.eval(*pointer) {
                        Value::Ptr(lv, None) => {
                            self.locals.insert(lv, v);
                        }
                        Value::Ptr(lv, Some(i)) => {
                            let mut whole = self.locals[&lv].scalars();
                            whole[i] = v.scalars()[0];
                            self.locals.insert(lv, Value::V(whole));
                        }
                        other => panic!("store to {other:?}"),
                    }
                }
                Statement::Call { function, arguments, result } => {
                    let args = arguments.iter().map(|a| self.eval(*a)).collect();
                    let v = call(self.module, &self.module.functions[*function], args);
                    if let Some(r) = result {
                        self.values.insert(*r, v);
                    }
                }
                other => panic!("unsupported statement {other:?}"),
            }
        }
        Flow::Next
    }
}

fn function<'a>(module: &'a naga::Module, name: &str) -> &'a naga::Function {
    module.functions.iter().map(|(_, f)| f).find(|f| f.name.as_deref() == Some(name)).expect(name)
}

/// The direction the shader decodes for `code` (one word up to 32 bits, else `lo, hi`), and its
/// named bindings.
fn run_decoder(module: &naga::Module, bits: u32, code: u64) -> (DVec3, HashMap<String, Value>) {
    let args = if bits <= 32 {
        vec![Value::S(Scalar::U(code as u32))]
    } else {
        vec![Value::S(Scalar::U(code as u32)), Value::S(Scalar::U((code >> 32) as u32))]
    };
    let (v, names) = call_with_names(module, function(module, "prtkit_decode_normal"), args);
    let v: Vec<f64> = v.scalars().into_iter().map(|s| float(s).into()).collect();
    (DVec3::new(v[0], v[1], v[2]), names)
}

/// The mixed-radix digits `(face, a, b)` of `code`, most significant first (`radix.rs`).
fn digits(codec: &Codec, code: u64) -> (u64, u64, u64) {
    let d = codec.digits();
    let (nb, na, faces) = (d[0].radix, d[1].radix, d.get(2).map_or(1, |f| f.radix));
    let rest = code / nb;
    ((rest / na).min(faces - 1), rest % na, code % nb)
}

/// Codes to test: random ones, the first and last, and every digit at its extremes.
fn codes(codec: &Codec, state: &mut SplitMix64) -> Vec<u64> {
    let mask = if codec.bits() == 64 { u64::MAX } else { (1u64 << codec.bits()) - 1 };
    let mut codes: Vec<u64> = (0..300).map(|_| state.next_u64() & mask).collect();
    codes.extend([0, 1, mask, mask - 1]);
    let mut place = 1u128;
    for d in codec.digits() {
        for v in [0, 1, d.radix / 2, d.radix - 2, d.radix - 1] {
            codes.push(((v as u128 * place) as u64) & mask);
        }
        place *= d.radix as u128;
    }
    codes
}

/// How far an f32 decoder may be from the f64 one at `rust`, the f64 decoding of `code`: a few
/// f32 ulps of the components (~1e-7 rad) and of SC's angles (`φ` of a 64-bit code is ~2^32
/// ulps), 2e-6 rad in all; and for PP and SPP, whose rebuilt component `m = sqrt(1 - a² - b²)`
/// turns the ~5·2^-24 rounding error `e` of `1 - a² - b²` in f32 into `min(√e, e/2m)`: up to
/// 5e-4 rad where `m → 0` (PP's equator, SPP's never-written codes beyond the sextant).
fn f32_tolerance(codec: &Codec, code: u64, rust: DVec3) -> f64 {
    let e = 5.0 * (-24f64).exp2();
    let digits = codec.digits();
    let m = match codec.scheme() {
        Scheme::Pp => rust.z.abs(),
        Scheme::Spp => {
            let face = (code as u128 / (digits[0].radix as u128 * digits[1].radix as u128)).min(5) as usize;
            rust[face / 2].abs()
        }
        _ => return 2e-6,
    };
    2e-6 + e.sqrt().min(e / (2.0 * m))
}

#[test]
fn emitted_decoders_decode_like_the_rust_decoder() {
    // The tolerance (f32_tolerance) is far below every step of a 33-bit code (~4e-5 rad) away
    // from PP's equator, so a wrong digit, face or axis at up to 32 bits cannot pass; above 32
    // bits the digits come from prtkit_divmod, tested exactly below.
    let mut state = SplitMix64::new(99);
    let (mut report, mut checked) = (String::new(), 0);
    for scheme in Scheme::ALL {
        for bits in BUDGETS {
            let codec = Codec::new(scheme, bits).unwrap();
            for (lang, module) in [("wgsl", wgsl_module(&codec)), ("glsl", glsl_module(&codec))] {
                let mut worst = 0f64;
                for code in codes(&codec, &mut state) {
                    let ((shader, names), rust) = (run_decoder(&module, bits, code), codec.decode(code));
                    // The integer digits exactly, where the shader names them as single words.
                    let (face, a, b) = digits(&codec, code);
                    for (name, want) in [("face", face), ("a", a), ("b", b)] {
                        if let Some(Value::S(Scalar::U(got))) = names.get(name) {
                            assert_eq!(*got as u64, want, "{lang} {scheme} {bits}, code {code:#x}: digit {name}");
                            checked += 1;
                        }
                    }
                    let (e, tolerance) = (angle_between(shader, rust), f32_tolerance(&codec, code, rust));
                    assert!(
                        e <= tolerance,
                        "{lang} {scheme} {bits}, code {code:#x}: {shader:?} vs {rust:?}: {e:e} rad"
                    );
                    worst = worst.max(e / tolerance);
                }
                report += &format!("{lang} {scheme} {bits}: error / tolerance <= {worst:.2}\n");
            }
        }
    }
    println!("{report}");
    // Every mixed-radix decoder names its digits (the SC ones of the widest budgets excepted).
    assert!(checked > 20_000, "{checked} digits checked");
}

#[test]
fn divmod_helper_divides_64_bit_codes_exactly() {
    // prtkit_divmod is the one piece of integer arithmetic that has no native shader operation;
    // it must agree with u64 division for every divisor the layouts use and for the extremes.
    let codec = Codec::new(Scheme::Sc, 64).unwrap();
    let mut state = SplitMix64::new(5);
    for (lang, module) in [("wgsl", wgsl_module(&codec)), ("glsl", glsl_module(&codec))] {
        let divmod = function(&module, "prtkit_divmod");
        let mut divisors: Vec<u64> = vec![2, 3, 6, 7, 65_537, (1 << 31) - 1, 1 << 31, (1 << 31) + 1, u32::MAX as u64];
        for scheme in [Scheme::Sc, Scheme::Pp, Scheme::Spp, Scheme::Cm] {
            for bits in [33, 40, 48, 56, 63, 64] {
                divisors.extend(
                    Codec::new(scheme, bits).unwrap().digits().iter().map(|d| d.radix).filter(|&r| r < 1 << 32),
                );
            }
        }
        for n in divisors {
            let mut xs: Vec<u64> = (0..40).map(|_| state.next_u64()).collect();
            xs.extend([0, 1, n - 1, n, n + 1, u64::MAX, u64::MAX - 1, (n << 32).wrapping_sub(1)]);
            for x in xs {
                let args = [x >> 32, x & 0xffff_ffff, n].map(|w| Value::S(Scalar::U(w as u32))).to_vec();
                let got: Vec<u64> = call(&module, divmod, args)
                    .scalars()
                    .into_iter()
                    .map(|s| match s {
                        Scalar::U(w) => w as u64,
                        other => panic!("{other:?}"),
                    })
                    .collect();
                assert_eq!(((got[0] << 32) | got[1], got[2]), (x / n, x % n), "{lang}: {x} / {n}");
            }
        }
    }
}
