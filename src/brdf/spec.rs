//! The one BRDF spec parser every stage uses (`docs/brdf-specs.md`).
//!
//! ```text
//! spec   := model | model ":" params | "merl:" path
//! params := key "=" number ("," key "=" number)*        (lafortune: lobe=a/b/c[/d], repeatable)
//! ```
//!
//! Parsing checks names and numbers without touching files; [`BrdfSpec::load`] reads MERL data.

use super::models::{BlinnPhong, KajiyaKay, Lafortune, LafortuneLobe, Lambert, Phong, TorranceSparrow};
use super::{Brdf, BrdfError};
use crate::limits::{MAX_BRDF_PEAK, MAX_TORRANCE_SPARROW_SIGMA};
use std::f64::consts::PI;
use std::fmt;
use std::path::{Path, PathBuf};

/// The models and their parameters, for error messages and `--help`.
pub const ACCEPTED: &str = "lambert[:albedo=A], phong:s=S, blinn-phong:s=S, torrance-sparrow:sigma=SIGMA, \
lafortune:[kd=KD,]lobe=CXY/CZ/N[,lobe=CX/CY/CZ/N...], kajiya-kay:s=S, merl:PATH";

/// A parsed BRDF spec: a model and its validated parameters (MERL data not yet read).
#[derive(Clone, Debug, PartialEq)]
pub enum BrdfSpec {
    /// `lambert[:albedo=A]`.
    Lambert(Lambert),
    /// `phong:s=S`.
    Phong(Phong),
    /// `blinn-phong:s=S`.
    BlinnPhong(BlinnPhong),
    /// `torrance-sparrow:sigma=SIGMA`.
    TorranceSparrow(TorranceSparrow),
    /// `lafortune:kd=KD,lobe=…`.
    Lafortune(Lafortune),
    /// `kajiya-kay:s=S`.
    KajiyaKay(KajiyaKay),
    /// `merl:PATH`.
    Merl(PathBuf),
}

/// A spec that does not parse. The message says what is wrong and what is accepted.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("invalid BRDF spec {spec:?}: {reason}")]
pub struct SpecError {
    /// The spec as given.
    pub spec: String,
    /// What is wrong, and what would be accepted.
    pub reason: String,
}

impl BrdfSpec {
    /// Parses a spec string.
    pub fn parse(spec: &str) -> Result<Self, SpecError> {
        let err = |reason: String| SpecError { spec: spec.to_string(), reason };
        let trimmed = spec.trim();
        let (model, rest) = match trimmed.split_once(':') {
            Some((m, r)) => (m.trim(), Some(r)),
            None => (trimmed, None),
        };
        let model_lc = model.to_ascii_lowercase();
        if model_lc == "merl" {
            let path = rest.map(str::trim).unwrap_or("");
            if path.is_empty() {
                return Err(err("merl needs a file: merl:path/to/material.binary".into()));
            }
            return Ok(BrdfSpec::Merl(PathBuf::from(path)));
        }
        let params = parse_params(rest.unwrap_or(""), spec)?;
        let mut p = Params { spec, model: model_lc.clone(), params, used: vec![] };
        p.check_known()?;
        let parsed = match model_lc.as_str() {
            "lambert" => {
                let albedo = p.optional("albedo", 1.0)?;
                if !(0.0..=1.0).contains(&albedo) {
                    return Err(err(format!("lambert albedo must be in [0, 1], got {albedo}")));
                }
                BrdfSpec::Lambert(Lambert { albedo })
            }
            "phong" => {
                let s = p.positive("s")?;
                p.peak("the lobe's peak (s+1)/(2π)", (s + 1.0) / (2.0 * PI), "s", 2.0 * PI * MAX_BRDF_PEAK - 1.0)?;
                BrdfSpec::Phong(Phong { exponent: s })
            }
            "blinn-phong" => {
                let s = p.positive("s")?;
                p.peak("the lobe's peak (s+2)/(8π)", (s + 2.0) / (8.0 * PI), "s", 8.0 * PI * MAX_BRDF_PEAK - 2.0)?;
                BrdfSpec::BlinnPhong(BlinnPhong { exponent: s })
            }
            "torrance-sparrow" => {
                let sigma = p.positive("sigma")?;
                let min_sigma = 1.0 / (4.0 * PI * MAX_BRDF_PEAK).sqrt();
                p.peak("the lobe's peak 1/(4πσ²)", 1.0 / (4.0 * PI * sigma * sigma), "sigma >=", min_sigma)?;
                if sigma > MAX_TORRANCE_SPARROW_SIGMA {
                    return Err(err(format!(
                        "sigma={sigma} is above the ceiling of {MAX_TORRANCE_SPARROW_SIGMA} (the lobe is flat long before; see docs/limits.md)"
                    )));
                }
                BrdfSpec::TorranceSparrow(TorranceSparrow { sigma })
            }
            "kajiya-kay" => {
                let s = p.positive("s")?;
                p.peak("the lobe's peak (s+1)/(2π)", (s + 1.0) / (2.0 * PI), "s", 2.0 * PI * MAX_BRDF_PEAK - 1.0)?;
                BrdfSpec::KajiyaKay(KajiyaKay { exponent: s })
            }
            "lafortune" => {
                let kd = p.optional("kd", 0.0)?;
                if kd < 0.0 {
                    return Err(err(format!("lafortune kd must be >= 0, got {kd}")));
                }
                p.peak("the diffuse term kd/π", kd / PI, "kd", PI * MAX_BRDF_PEAK)?;
                let lobes = p.lobes()?;
                for l in &lobes {
                    // max |C·(ω_i ⊙ ω_o)| ≤ max |C| for unit directions: the lobe's peak is at
                    // most (max |C|)^n (compared in logarithms: the power itself may overflow).
                    let c = l.cx.abs().max(l.cy.abs()).max(l.cz.abs());
                    if c > 0.0 && l.exponent * c.ln() > MAX_BRDF_PEAK.ln() {
                        return Err(err(format!(
                            "lobe {}/{}/{}/{}: its peak (max |C|)^n = {c}^{} is above the ceiling of {MAX_BRDF_PEAK:e} sr^-1 \
                             (see docs/limits.md)",
                            l.cx, l.cy, l.cz, l.exponent, l.exponent
                        )));
                    }
                }
                BrdfSpec::Lafortune(Lafortune { kd, lobes })
            }
            "" => return Err(err(format!("empty model name; accepted: {ACCEPTED}"))),
            other => return Err(err(format!("unknown BRDF model {other:?}; accepted: {ACCEPTED}"))),
        };
        p.finish()?;
        Ok(parsed)
    }

    /// The model name, e.g. `phong`.
    pub fn model_name(&self) -> &'static str {
        match self {
            BrdfSpec::Lambert(_) => "lambert",
            BrdfSpec::Phong(_) => "phong",
            BrdfSpec::BlinnPhong(_) => "blinn-phong",
            BrdfSpec::TorranceSparrow(_) => "torrance-sparrow",
            BrdfSpec::Lafortune(_) => "lafortune",
            BrdfSpec::KajiyaKay(_) => "kajiya-kay",
            BrdfSpec::Merl(_) => "merl",
        }
    }

    /// Makes a relative MERL path relative to `base` (e.g. a manifest's directory).
    pub fn resolve_relative_to(self, base: &Path) -> Self {
        match self {
            BrdfSpec::Merl(p) if p.is_relative() => BrdfSpec::Merl(base.join(p)),
            other => other,
        }
    }

    /// Builds the BRDF, reading MERL data from disk.
    pub fn load(&self) -> Result<Brdf, BrdfError> {
        Ok(match self {
            BrdfSpec::Lambert(m) => Brdf::Lambert(*m),
            BrdfSpec::Phong(m) => Brdf::Phong(*m),
            BrdfSpec::BlinnPhong(m) => Brdf::BlinnPhong(*m),
            BrdfSpec::TorranceSparrow(m) => Brdf::TorranceSparrow(*m),
            BrdfSpec::Lafortune(m) => Brdf::Lafortune(m.clone()),
            BrdfSpec::KajiyaKay(m) => Brdf::KajiyaKay(*m),
            BrdfSpec::Merl(path) => Brdf::Merl(std::sync::Arc::new(super::merl::MerlBrdf::read(path)?)),
        })
    }
}

/// Canonical spec string (parses back to the same spec).
impl fmt::Display for BrdfSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BrdfSpec::Lambert(m) if m.albedo == 1.0 => write!(f, "lambert"),
            BrdfSpec::Lambert(m) => write!(f, "lambert:albedo={}", m.albedo),
            BrdfSpec::Phong(m) => write!(f, "phong:s={}", m.exponent),
            BrdfSpec::BlinnPhong(m) => write!(f, "blinn-phong:s={}", m.exponent),
            BrdfSpec::TorranceSparrow(m) => write!(f, "torrance-sparrow:sigma={}", m.sigma),
            BrdfSpec::KajiyaKay(m) => write!(f, "kajiya-kay:s={}", m.exponent),
            BrdfSpec::Lafortune(m) => {
                write!(f, "lafortune:kd={}", m.kd)?;
                for l in &m.lobes {
                    if l.cx == l.cy {
                        write!(f, ",lobe={}/{}/{}", l.cx, l.cz, l.exponent)?;
                    } else {
                        write!(f, ",lobe={}/{}/{}/{}", l.cx, l.cy, l.cz, l.exponent)?;
                    }
                }
                Ok(())
            }
            BrdfSpec::Merl(p) => write!(f, "merl:{}", p.display()),
        }
    }
}

fn parse_params(text: &str, spec: &str) -> Result<Vec<(String, String)>, SpecError> {
    let mut out = Vec::new();
    if text.trim().is_empty() {
        return Ok(out);
    }
    for item in text.split(',') {
        let item = item.trim();
        let (k, v) = item.split_once('=').ok_or_else(|| SpecError {
            spec: spec.to_string(),
            reason: format!("parameter {item:?} is not key=value (e.g. phong:s=30)"),
        })?;
        out.push((k.trim().to_ascii_lowercase(), v.trim().to_string()));
    }
    Ok(out)
}

struct Params<'a> {
    spec: &'a str,
    model: String,
    params: Vec<(String, String)>,
    used: Vec<String>,
}

impl Params<'_> {
    fn err(&self, reason: String) -> SpecError {
        SpecError { spec: self.spec.to_string(), reason }
    }

    fn accepted(&self) -> &'static str {
        match self.model.as_str() {
            "lambert" => "albedo (in [0, 1], default 1)",
            "phong" | "blinn-phong" | "kajiya-kay" => "s (exponent > 0)",
            "torrance-sparrow" => "sigma (roughness > 0, radians)",
            "lafortune" => "kd (>= 0, default 0) and lobe=CXY/CZ/N or lobe=CX/CY/CZ/N (N > 0), repeatable",
            _ => "",
        }
    }

    /// Rejects parameters the model does not take, before any is required.
    fn check_known(&self) -> Result<(), SpecError> {
        let known: &[&str] = match self.model.as_str() {
            "lambert" => &["albedo"],
            "phong" | "blinn-phong" | "kajiya-kay" => &["s"],
            "torrance-sparrow" => &["sigma"],
            "lafortune" => &["kd", "lobe"],
            _ => return Ok(()),
        };
        if let Some((k, _)) = self.params.iter().find(|(k, _)| !known.contains(&k.as_str())) {
            return Err(self.err(format!(
                "{} does not take parameter {k:?}; accepted: {}",
                self.model,
                self.accepted()
            )));
        }
        Ok(())
    }

    fn number(&self, key: &str, value: &str) -> Result<f64, SpecError> {
        let x: f64 = value.parse().map_err(|_| self.err(format!("{key}={value:?} is not a number")))?;
        if !x.is_finite() {
            return Err(self.err(format!("{key}={value} is not finite")));
        }
        Ok(x)
    }

    fn single(&mut self, key: &str) -> Result<Option<f64>, SpecError> {
        let hits: Vec<String> = self.params.iter().filter(|(k, _)| k == key).map(|(_, v)| v.clone()).collect();
        if hits.len() > 1 {
            return Err(self.err(format!("parameter {key} is given {} times", hits.len())));
        }
        self.used.push(key.to_string());
        hits.first().map(|v| self.number(key, v)).transpose()
    }

    fn optional(&mut self, key: &str, default: f64) -> Result<f64, SpecError> {
        Ok(self.single(key)?.unwrap_or(default))
    }

    /// Refuses parameters whose BRDF peak exceeds [`MAX_BRDF_PEAK`] (`docs/limits.md`):
    /// `limit` is the ceiling of parameter `key` it amounts to.
    fn peak(&self, what: &str, peak: f64, key: &str, limit: f64) -> Result<(), SpecError> {
        if peak > MAX_BRDF_PEAK {
            return Err(self.err(format!(
                "{what} = {peak:.3e} is above the ceiling of {MAX_BRDF_PEAK:e} sr^-1 ({key} {limit:.3e} at most; \
                 no stage resolves a narrower lobe, see docs/limits.md)"
            )));
        }
        Ok(())
    }

    fn positive(&mut self, key: &str) -> Result<f64, SpecError> {
        match self.single(key)? {
            None => Err(self.err(format!("{} needs {key}: accepted parameters: {}", self.model, self.accepted()))),
            Some(x) if x <= 0.0 => Err(self.err(format!("{key} must be > 0, got {x}"))),
            Some(x) => Ok(x),
        }
    }

    fn lobes(&mut self) -> Result<Vec<LafortuneLobe>, SpecError> {
        self.used.push("lobe".into());
        let mut lobes = Vec::new();
        for (_, v) in self.params.iter().filter(|(k, _)| k == "lobe") {
            let parts: Vec<&str> = v.split('/').map(str::trim).collect();
            let nums = parts.iter().map(|p| self.number("lobe", p)).collect::<Result<Vec<f64>, _>>()?;
            let lobe = match nums.as_slice() {
                [cxy, cz, n] => LafortuneLobe { cx: *cxy, cy: *cxy, cz: *cz, exponent: *n },
                [cx, cy, cz, n] => LafortuneLobe { cx: *cx, cy: *cy, cz: *cz, exponent: *n },
                _ => {
                    return Err(self.err(format!(
                        "lobe={v:?} needs 3 (CXY/CZ/N) or 4 (CX/CY/CZ/N) numbers separated by '/', got {}",
                        nums.len()
                    )))
                }
            };
            if lobe.exponent <= 0.0 {
                return Err(self.err(format!("lobe exponent must be > 0, got {}", lobe.exponent)));
            }
            lobes.push(lobe);
        }
        if lobes.is_empty() {
            return Err(self.err("lafortune needs at least one lobe, e.g. lafortune:kd=0.1,lobe=-1/1/20".into()));
        }
        Ok(lobes)
    }

    fn finish(self) -> Result<(), SpecError> {
        if let Some((k, _)) = self.params.iter().find(|(k, _)| !self.used.contains(k)) {
            let accepted = self.accepted();
            return Err(self.err(format!("{} does not take parameter {k:?}; accepted: {accepted}", self.model)));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_every_model_and_prints_it_back() {
        for s in [
            "lambert",
            "lambert:albedo=0.5",
            "phong:s=30",
            "blinn-phong:s=64",
            "torrance-sparrow:sigma=0.2",
            "kajiya-kay:s=32",
            "lafortune:kd=0.1,lobe=-1/1/20",
            "lafortune:kd=0,lobe=-1/-0.5/1/20,lobe=-0.8/0.8/4",
            "merl:some dir/gold-metallic-paint.binary",
        ] {
            let spec = BrdfSpec::parse(s).unwrap();
            let again = BrdfSpec::parse(&spec.to_string()).unwrap();
            assert_eq!(spec, again, "{s}");
        }
        assert_eq!(BrdfSpec::parse(" Phong : s = 30 ").unwrap(), BrdfSpec::Phong(Phong { exponent: 30.0 }));
    }

    #[test]
    fn errors_say_what_is_wrong_and_what_is_accepted() {
        let e = |s: &str| BrdfSpec::parse(s).unwrap_err().to_string();
        assert!(e("glossy:s=3").contains("unknown BRDF model \"glossy\"") && e("glossy").contains("phong:s=S"));
        assert!(e("phong").contains("phong needs s"));
        assert!(e("phong:s=0").contains("s must be > 0"));
        assert!(e("phong:s=-3").contains("s must be > 0"));
        assert!(e("phong:s=abc").contains("not a number"));
        assert!(e("phong:s=inf").contains("not finite"));
        assert!(e("phong:s=3,s=4").contains("2 times"));
        assert!(e("phong:exponent=3").contains("does not take parameter \"exponent\""));
        assert!(e("torrance-sparrow:s=0.2").contains("sigma"));
        assert!(e("lafortune:kd=0.1").contains("at least one lobe"));
        assert!(e("lafortune:lobe=1/2").contains("needs 3"));
        assert!(e("lambert:albedo=2").contains("[0, 1]"));
        assert!(e("merl:").contains("merl needs a file"));
        assert!(e("phong:30").contains("key=value"));
        // Ceilings (docs/limits.md): a lobe too tall for f64 energy sums, or too flat to matter.
        assert!(e("phong:s=1e308").contains("above the ceiling of 1e8"), "{}", e("phong:s=1e308"));
        assert!(e("blinn-phong:s=1e10").contains("ceiling"));
        assert!(e("kajiya-kay:s=1e300").contains("ceiling"));
        assert!(e("torrance-sparrow:sigma=1e-300").contains("sigma >="));
        assert!(e("torrance-sparrow:sigma=1e200").contains("ceiling of 100"));
        assert!(e("lafortune:kd=1e300,lobe=-1/1/2").contains("kd/π"));
        assert!(e("lafortune:lobe=-2/2/1e9").contains("(max |C|)^n"));
        for ok in ["phong:s=1e8", "blinn-phong:s=1e8", "torrance-sparrow:sigma=1e-4", "lafortune:lobe=-0.5/0.5/1e12"] {
            assert!(BrdfSpec::parse(ok).is_ok(), "{ok}");
        }
    }
}
