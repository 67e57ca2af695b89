//! The shading language (`docs/shading-language.md`): lexer, parser, checker, one interpreter
//! generic over the number type, and the adaptive quadtree sampler of Heidrich, Slusallek &
//! Seidel 1998.

pub mod check;
pub mod interp;
pub mod lexer;
pub mod noise;
pub mod parser;
pub mod report;
pub mod sampler;
pub mod stage;

use crate::affine::Real;
use check::Checked;
use interp::{Globals, Value};
use lexer::Pos;
use parser::Type;

/// A compile or runtime error of a shader, at a line and column — or, for errors of a
/// parameter override (line 0), naming the override `-p NAME=VALUE` in the message instead.
#[derive(Clone, Debug, PartialEq)]
pub struct ShaderError {
    /// The source file, when known.
    pub file: Option<String>,
    /// Where (line 0: no place in the source; the message says what it concerns).
    pub pos: Pos,
    /// What.
    pub message: String,
}

impl std::fmt::Display for ShaderError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match (&self.file, self.pos.line) {
            (Some(file), 0) => write!(f, "{file}: {}", self.message),
            (None, 0) => write!(f, "{}", self.message),
            (file, line) => {
                let file = file.as_deref().map(|f| format!("{f}:")).unwrap_or_default();
                write!(f, "{file}{line}:{}: {}", self.pos.col, self.message)
            }
        }
    }
}

impl std::error::Error for ShaderError {}

impl ShaderError {
    /// An error at `pos`.
    pub fn at(pos: Pos, message: impl Into<String>) -> ShaderError {
        ShaderError { file: None, pos, message: message.into() }
    }
    fn in_file(mut self, file: &str) -> ShaderError {
        self.file = Some(file.to_string());
        self
    }
}

/// Reads a shader's source: at most [`crate::limits::MAX_SHADER_SOURCE_BYTES`], UTF-8.
pub fn read_source(path: &std::path::Path) -> Result<String, crate::io::IoError> {
    crate::io::read_text(path, "shader", crate::limits::MAX_SHADER_SOURCE_BYTES, |_| Ok(()))
}

/// A compiled shader with its parameter values.
#[derive(Clone, Debug)]
pub struct Shader {
    program: Checked,
    params: Vec<Value<f64>>,
    file: String,
}

/// A parameter's current value, for reports.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ParamValue {
    /// Name.
    pub name: String,
    /// Type name.
    #[serde(rename = "type")]
    pub ty: String,
    /// Value (1 or 3 numbers).
    pub value: Vec<f64>,
}

impl Shader {
    /// Compiles `source`; errors name `file`, line and column.
    pub fn compile(source: &str, file: &str) -> Result<Shader, ShaderError> {
        let prog = parser::parse(source).map_err(|e| e.in_file(file))?;
        let program = check::check(&prog).map_err(|e| e.in_file(file))?;
        let mut shader = Shader { program, params: Vec::new(), file: file.to_string() };
        shader.set_params(&[])?;
        Ok(shader)
    }

    /// Sets parameters from `name=value` overrides (a number, or `r,g,b` for triples); the
    /// others take their defaults (which may use earlier parameters). An error in an override
    /// names it as `-p NAME=VALUE`, the form `sample-shader` takes it in.
    pub fn set_params(&mut self, overrides: &[(String, String)]) -> Result<(), ShaderError> {
        let bad = |name: &str, value: &str, message: String| {
            ShaderError::at(Pos::default(), format!("-p {name}={value}: {message}")).in_file(&self.file)
        };
        for (name, value) in overrides {
            if !self.program.params.iter().any(|p| &p.name == name) {
                let known: Vec<&str> = self.program.params.iter().map(|p| p.name.as_str()).collect();
                let has =
                    if known.is_empty() { "no parameters".to_string() } else { format!("has: {}", known.join(", ")) };
                return Err(bad(
                    name,
                    value,
                    format!("unknown parameter '{name}' (shader '{}' {has})", self.program.name),
                ));
            }
        }
        let mut frame: Vec<Value<f64>> = Vec::new();
        for p in &self.program.params {
            let value = match overrides.iter().rev().find(|(n, _)| n == &p.name) {
                Some((_, text)) => parse_value(text, p.ty).map_err(|m| bad(&p.name, text, m))?,
                None => interp::eval_const(&self.program, &p.default, &frame).map_err(|e| e.in_file(&self.file))?,
            };
            frame.push(value);
        }
        self.params = frame;
        Ok(())
    }

    /// The shader's name.
    pub fn name(&self) -> &str {
        &self.program.name
    }

    /// Whether the shader reads the direction D (meant for lat-long sampling).
    pub fn uses_direction(&self) -> bool {
        self.program.uses_direction
    }

    /// Current parameter values.
    pub fn params(&self) -> Vec<ParamValue> {
        self.program
            .params
            .iter()
            .zip(&self.params)
            .map(|(p, v)| ParamValue {
                name: p.name.clone(),
                ty: p.ty.name().to_string(),
                value: match v {
                    Value::F(x) => vec![*x],
                    Value::T(t) => t.to_vec(),
                    Value::B(_) => Vec::new(),
                },
            })
            .collect()
    }

    /// Evaluates Ci for one sample in arithmetic `N`; runtime limits report line and column.
    pub fn eval<N: Real>(&self, g: &Globals<N>) -> Result<[N; 3], ShaderError> {
        interp::run(&self.program, &self.params, g).map_err(|e| e.in_file(&self.file))
    }
}

fn parse_value(text: &str, ty: Type) -> Result<Value<f64>, String> {
    let nums: Result<Vec<f64>, _> = text.split(',').map(|s| s.trim().parse::<f64>()).collect();
    let nums = nums.map_err(|_| format!("cannot read {text:?} as a number (or r,g,b)"))?;
    if nums.iter().any(|x| !x.is_finite()) {
        return Err(format!("value {text:?} is not finite"));
    }
    match (ty, nums.len()) {
        (Type::Float, 1) => Ok(Value::F(nums[0])),
        (Type::Float, n) => Err(format!("expected one number for a float, found {n}")),
        (_, 1) => Ok(Value::T([nums[0]; 3])),
        (_, 3) => Ok(Value::T([nums[0], nums[1], nums[2]])),
        (t, n) => Err(format!("expected 1 or 3 numbers for a {}, found {n}", t.name())),
    }
}

#[cfg(test)]
mod tests {
    use super::sampler::{point_value, Domain};
    use super::*;

    fn err(src: &str) -> String {
        match Shader::compile(src, "t.sl") {
            Ok(_) => String::from("<compiled>"),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn errors_carry_line_and_column() {
        assert_eq!(err("shader s() {\n  Ci = 1 +;\n}"), "t.sl:2:11: expected an expression, found ';'");
        assert_eq!(err("shader s() {\n  float x = y;\n}"), "t.sl:2:13: unknown variable 'y'");
        assert_eq!(
            err("shader s() {\n  color c = P;\n}"),
            "t.sl:2:13: initial value of 'c': expected color, found point"
        );
        assert_eq!(
            err("shader s() {\n  Ci = color(1) + P;\n}"),
            "t.sl:2:8: operator '+': cannot combine color and point (convert explicitly)"
        );
        assert_eq!(err("shader s() {\n  Ci = 1; @\n}"), "t.sl:2:11: unexpected character '@'");
        assert!(err("shader s(float k = 2) {\n  for (float i = 0; i < u; i += 1) { Ci = 1; }\n}")
            .starts_with("t.sl:2:25: the loop bound must be constant"));
        assert!(err("float f(float x) { if (x < 0) { return 1; } return 2; }\nshader s() { Ci = f(u); }")
            .starts_with("t.sl:1:33: 'return' must be the last"));
        assert_eq!(
            err("shader s(float k = 1) {\n  k = 2;\n}"),
            "t.sl:2:3: 'k' is a parameter or loop variable and cannot be assigned"
        );
    }

    #[test]
    fn parameters_default_and_override() {
        let src = "shader s(float a = 2, float b = a * 3, color c = color(0.5, 0.25, 1)) { Ci = c * b; }";
        let mut s = Shader::compile(src, "t.sl").unwrap_or_else(|e| panic!("{e}"));
        let ci = point_value(&s, Domain::Texture, 0.5, 0.5, 0.0, 0.0).unwrap_or([f64::NAN; 3]);
        assert_eq!(ci, [3.0, 1.5, 6.0]);
        s.set_params(&[("a".into(), "1".into()), ("c".into(), "1,2,3".into())]).unwrap_or_else(|e| panic!("{e}"));
        let ci = point_value(&s, Domain::Texture, 0.5, 0.5, 0.0, 0.0).unwrap_or([f64::NAN; 3]);
        assert_eq!(ci, [3.0, 6.0, 9.0]);
        let e = s.set_params(&[("nope".into(), "1".into())]).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(e.contains("unknown parameter 'nope'") && e.contains("a, b, c"), "{e}");
    }

    #[test]
    fn language_evaluates_like_a_reference() {
        // Loops, user functions, if/else, mod, spline through knots, builtins.
        let src = "float sq(float x) { return x * x; }
            shader s(float n = 4) {
                float acc = 0;
                for (float i = 0; i < n; i += 1) { acc += sq(i); }
                float m = mod(-0.25, 1);
                float sp = spline(0.5, 0, 0, 1, 2, 2);
                if (u > 0.5) { acc = acc + 100; } else { acc = acc - 100; }
                Ci = color(acc, m, sp);
            }";
        let s = Shader::compile(src, "t.sl").unwrap_or_else(|e| panic!("{e}"));
        let ci = point_value(&s, Domain::Texture, 0.75, 0.5, 0.0, 0.0).unwrap_or([f64::NAN; 3]);
        // 0+1+4+9 = 14; mod(−0.25, 1) = 0.75; Catmull-Rom at the middle knot of 0,0,1,2,2 = 1.
        assert_eq!(ci, [114.0, 0.75, 1.0]);
    }

    #[test]
    fn runaway_recursion_and_loops_hit_clear_limits() {
        let rec = "float f(float x) { return f(x + 1); }\nshader s() { Ci = f(u); }";
        let s = Shader::compile(rec, "t.sl").unwrap_or_else(|e| panic!("{e}"));
        let e = point_value(&s, Domain::Texture, 0.5, 0.5, 0.0, 0.0).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(e.starts_with("t.sl:1:27: recursion limit"), "{e}");
        let lp = "shader s() {\n float a = 0;\n for (float i = 0; i < 1e9; i += 1) { a += 1; }\n Ci = a; }";
        let s = Shader::compile(lp, "t.sl").unwrap_or_else(|e| panic!("{e}"));
        let e = point_value(&s, Domain::Texture, 0.5, 0.5, 0.0, 0.0).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(e.starts_with("t.sl:3:2: loop limit"), "{e}");
    }

    #[test]
    fn division_by_a_range_with_zero_is_unbounded_not_a_panic() {
        let s = Shader::compile("shader s() { Ci = 1 / (u - 0.5); }", "t.sl").unwrap_or_else(|e| panic!("{e}"));
        let g = sampler::globals::<crate::affine::Affine>(Domain::Texture, [0.0, 1.0], [0.0, 1.0]);
        let ci = s.eval(&g).unwrap_or_else(|e| panic!("{e}"));
        assert!(ci[0].range().lo == f64::NEG_INFINITY && ci[0].range().hi == f64::INFINITY);
        // At exactly u = 0.5 the point value is 0 (x/0 = 0), inside the bound.
        assert_eq!(point_value(&s, Domain::Texture, 0.5, 0.5, 0.0, 0.0).unwrap_or([1.0; 3])[0], 0.0);
        // Clamping afterwards gives finite bounds again.
        let s = Shader::compile("shader s() { Ci = clamp(1 / (u - 0.5), 0, 1); }", "t.sl")
            .unwrap_or_else(|e| panic!("{e}"));
        let ci = s.eval(&g).unwrap_or_else(|e| panic!("{e}"));
        assert!(ci[0].range().lo >= 0.0 && ci[0].range().hi <= 1.0 + 1e-12);
    }
}

#[cfg(test)]
mod limits_tests {
    //! The ceilings of docs/limits.md for the shading language: nesting, recursion, the
    //! operation budget, runaway noise arguments.
    use super::sampler::{globals, point_value, Domain};
    use super::*;
    use crate::affine::{Affine, Interval};
    use crate::limits::{MAX_NESTING_DEPTH, MAX_OPERATIONS};

    fn nested(open: &str, inner: &str, close: &str, n: usize) -> String {
        format!("shader s() {{\n  Ci = {}{inner}{};\n}}", open.repeat(n), close.repeat(n))
    }

    /// Evaluates in all three arithmetics over a small box.
    fn eval_all(s: &Shader) -> Vec<Result<[f64; 3], ShaderError>> {
        let a = s.eval(&globals::<Affine>(Domain::LatLong, [0.1, 0.2], [0.3, 0.4])).map(|c| c.map(|x| x.range().lo));
        let i = s.eval(&globals::<Interval>(Domain::LatLong, [0.1, 0.2], [0.3, 0.4])).map(|c| c.map(|x| x.lo));
        vec![a, i, point_value(s, Domain::Texture, 0.3, 0.4, 0.0, 0.0)]
    }

    #[test]
    fn nesting_past_the_ceiling_is_an_error_at_its_position() {
        // The shapes: a 600-term sum, 248 nested abs( (fine now: under the ceiling, on a
        // small stack), 300 nested abs(, ~950 nested blocks.
        let sum = format!("shader s() {{\n  Ci = u{};\n}}", " + u".repeat(599));
        let e = Shader::compile(&sum, "t.sl").err().map(|e| e.to_string()).unwrap_or_default();
        // The statement and its expression take two levels, each operator one more: operator
        // k (at column 10 + 4(k − 1): "  Ci = u" then " + u" each) is level k + 2.
        let col = 10 + 4 * (MAX_NESTING_DEPTH - 2);
        assert!(e.starts_with(&format!("t.sl:2:{col}: nested deeper than {MAX_NESTING_DEPTH} levels")), "{e}");
        let e =
            Shader::compile(&nested("abs(", "u", ")", 300), "t.sl").err().map(|e| e.to_string()).unwrap_or_default();
        assert!(e.contains("nested deeper than"), "{e}");
        let blocks = format!("shader s() {{ {} Ci = u; {} }}", "{ ".repeat(950), "} ".repeat(950));
        let e = Shader::compile(&blocks, "t.sl").err().map(|e| e.to_string()).unwrap_or_default();
        assert!(e.starts_with("t.sl:1:") && e.contains("nested deeper than"), "{e}");
        let neg = nested("-", "u", "", 400);
        assert!(Shader::compile(&neg, "t.sl").is_err());
    }

    #[test]
    fn shaders_at_the_ceiling_compile_and_evaluate_on_a_1_mib_stack() {
        // Half of a rayon worker's 2 MiB: the stack claim of docs/limits.md.
        let depth = MAX_NESTING_DEPTH - 2;
        let sources = [
            nested("abs(", "u", ")", depth),
            nested("mix(u, v, ", "u", ")", depth),
            format!("shader s() {{ Ci = u{}; }}", " + u".repeat(depth - 1)),
            format!(
                "shader s() {{ {} Ci = u; {} }}",
                "{ if (u < 0.5) ".repeat(depth / 2 - 1),
                "} ".repeat(depth / 2 - 1)
            ),
            format!(
                "float f(float x) {{ return {}x{}; }}\nshader s() {{ Ci = f(f(u)); }}",
                "abs(".repeat(depth - 3),
                ")".repeat(depth - 3)
            ),
        ];
        let handle = std::thread::Builder::new()
            .stack_size(1 << 20)
            .spawn(move || {
                for src in sources {
                    let s = Shader::compile(&src, "t.sl").unwrap_or_else(|e| panic!("{e}"));
                    for r in eval_all(&s) {
                        // Either a value or a clear evaluation error; a stack overflow aborts the test.
                        if let Err(e) = r {
                            assert!(e.message.contains("nesting limit"), "{e}");
                        }
                    }
                }
            })
            .unwrap_or_else(|e| panic!("{e}"));
        assert!(handle.join().is_ok());
    }

    #[test]
    fn exponential_recursion_stops_at_the_operation_budget_naming_the_call() {
        let src = "float f(float x) {\n  float r = 1;\n  if (x > 0) { r = f(x - 1) + f(x - 1); }\n  return r;\n}\nshader s() {\n  Ci = f(40);\n}";
        let s = Shader::compile(src, "t.sl").unwrap_or_else(|e| panic!("{e}"));
        for r in eval_all(&s) {
            let e = r.err().map(|e| e.to_string()).unwrap_or_default();
            assert!(e.starts_with("t.sl:3:") && e.contains(&format!("more than {MAX_OPERATIONS} operations")), "{e}");
            assert!(e.contains("in a call of 'f'"), "{e}");
        }
        // f(10): 2^11 calls, well within the budget, and the value 2^10.
        let s = Shader::compile(&src.replace("f(40)", "f(10)"), "t.sl").unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(point_value(&s, Domain::Texture, 0.5, 0.5, 0.0, 0.0).ok(), Some([1024.0; 3]));
        // Nested loops: 10^5 iterations (within the loop limit) of ~15 operations.
        let lp = "shader s() {\n float a = 0;\n for (float i = 0; i < 100; i += 1) {\n  for (float j = 0; j < 1000; j += 1) { a += i * j + 1 + i * i + j * j; }\n }\n Ci = a;\n}";
        let s = Shader::compile(lp, "t.sl").unwrap_or_else(|e| panic!("{e}"));
        let e = point_value(&s, Domain::Texture, 0.5, 0.5, 0.0, 0.0).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(e.starts_with("t.sl:4:3: evaluation budget"), "{e}");
        // A step of 0 or of the wrong sign is refused before the first iteration.
        for step in ["i += 0", "i -= 1"] {
            let lp =
                format!("shader s() {{\n float a = 0;\n for (float i = 0; i < 3; {step}) {{ a += 1; }}\n Ci = a;\n}}");
            let s = Shader::compile(&lp, "t.sl").unwrap_or_else(|e| panic!("{e}"));
            let e =
                point_value(&s, Domain::Texture, 0.5, 0.5, 0.0, 0.0).err().map(|e| e.to_string()).unwrap_or_default();
            assert!(e.starts_with("t.sl:3:2: loop limit"), "{e}");
        }
    }

    #[test]
    fn noise_of_huge_or_unbounded_arguments_terminates_within_its_bound() {
        for src in [
            "shader s() { Ci = color(snoise(P * 1e12)); }",
            "shader s() { Ci = color(snoise(u * 1e300, v * 1e300)); }",
            "shader s() { Ci = color(noise(u * 1e19)); }",
            "shader s() { Ci = color(snoise(P * 1e12 + 1e18)); }",
            "shader s() { Ci = color(fbm(P * 1e12, 16, 1e30, 0.5)); }",
            "shader s() { Ci = color(sin(u * 1e17) + cos(1e20 + u)); }",
            "shader s() { Ci = color(snoise(1 / (u - 0.35))); }",
        ] {
            let s = Shader::compile(src, "t.sl").unwrap_or_else(|e| panic!("{src}: {e}"));
            for (k, r) in eval_all(&s).into_iter().enumerate() {
                let ci = r.unwrap_or_else(|e| panic!("{src}: {e}"));
                if !src.contains("fbm") && !src.contains("sin") {
                    assert!(ci[0].abs() <= 2.0 + 1e-9 || ci[0].is_nan(), "{src} ({k}): {ci:?}");
                }
            }
        }
    }

    #[test]
    fn parameter_errors_name_the_override() {
        let mut s = Shader::compile("shader wood(float ringscale = 10) { Ci = u * ringscale; }", "wood.sl")
            .unwrap_or_else(|e| panic!("{e}"));
        let e = s.set_params(&[("ringscale".into(), "abc".into())]).err().map(|e| e.to_string()).unwrap_or_default();
        assert_eq!(e, "wood.sl: -p ringscale=abc: cannot read \"abc\" as a number (or r,g,b)");
        let e = s.set_params(&[("rings".into(), "1".into())]).err().map(|e| e.to_string()).unwrap_or_default();
        assert_eq!(e, "wood.sl: -p rings=1: unknown parameter 'rings' (shader 'wood' has: ringscale)");
        assert!(!e.contains(":0:0"));
    }
}

#[cfg(test)]
mod conservativeness {
    //! Every shader in testdata/shaders: sample a quadtree in affine and in interval arithmetic and
    //! check 10⁵ random point evaluations (spread over every leaf, plus each leaf's corners)
    //! against the leaves' bounds: zero violations.
    use super::report::verify;
    use super::sampler::{sample, Arith, Domain, SampleConfig};
    use super::Shader;
    use crate::progress::NoProgress;

    #[test]
    fn every_leaf_of_every_shader_bounds_its_point_values() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("testdata/shaders");
        let mut names: Vec<_> = std::fs::read_dir(&dir)
            .map(|d| {
                d.filter_map(|e| e.ok())
                    .map(|e| e.path())
                    .filter(|p| p.extension().is_some_and(|x| x == "sl"))
                    .collect()
            })
            .unwrap_or_default();
        names.sort();
        assert!(names.len() >= 6, "expected the six shaders in {}", dir.display());
        for path in names {
            let src = std::fs::read_to_string(&path).unwrap_or_default();
            let shader = Shader::compile(&src, &path.display().to_string()).unwrap_or_else(|e| panic!("{e}"));
            let domain = if shader.uses_direction() { Domain::LatLong } else { Domain::Texture };
            for arith in [Arith::Affine, Arith::Interval] {
                let cfg = SampleConfig { tolerance: 0.1, max_depth: 4, arith, domain, points_per_node: 1, seed: 9 };
                let sampled = sample(&shader, &cfg, &NoProgress).unwrap_or_else(|e| panic!("{e}"));
                let per_leaf = 100_000usize.div_ceil(sampled.leaves.len());
                let v = verify(&shader, &sampled, domain, per_leaf, 11).unwrap_or_else(|e| panic!("{e}"));
                assert!(v.points >= 100_000);
                assert_eq!(v.violations, 0, "{} ({arith:?}): {v:?}", path.display());
            }
        }
    }
}
