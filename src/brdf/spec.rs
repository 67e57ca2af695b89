//! The one BRDF spec parser every stage uses (`docs/brdf-specs.md`), and its inverse: the
//! canonical spec string a [`Brdf`] prints as (`Display`), which the documents record.
//!
//! ```text
//! spec   := model | model ":" params | "merl:" path
//! params := key "=" number ("," key "=" number)*        (lafortune: lobe=a/b/c[/d], repeatable)
//! ```
//!
//! Names and numbers are checked before any file is touched; `merl:` then reads the table.

use super::models::{
    BlinnPhong, GgxMicrofacet, GltfMaterial, KajiyaKay, Lafortune, LafortuneLobe, Lambert, Phong, TorranceSparrow,
};
use super::{Brdf, BrdfError, MerlBrdf};
use crate::limits::{MAX_BRDF_PEAK, MAX_TORRANCE_SPARROW_SIGMA};
use std::f64::consts::PI;
use std::fmt;
use std::path::Path;
use std::sync::Arc;

/// The models and their parameters, for error messages and `--help`.
pub const ACCEPTED: &str = "lambert[:albedo=A], phong:s=S, blinn-phong:s=S, torrance-sparrow:sigma=SIGMA, \
lafortune:[kd=KD,]lobe=CXY/CZ/N[,lobe=CX/CY/CZ/N...], kajiya-kay:s=S, ggx:roughness=R, \
gltf[:base=R/G/B,metalness=M,roughness=R], merl:PATH";

/// The model names a spec can start with.
const MODELS: [&str; 9] =
    ["lambert", "phong", "blinn-phong", "torrance-sparrow", "lafortune", "kajiya-kay", "ggx", "gltf", "merl"];

/// The model a misspelled name most likely meant: the nearest by edit distance, if within a
/// third of its length (one slip in `ggx`, three in `torrance-sparrow`).
fn did_you_mean(name: &str) -> Option<&'static str> {
    let name = name.to_ascii_lowercase();
    MODELS
        .into_iter()
        .map(|m| (strsim::levenshtein(&name, m), m))
        .filter(|&(d, m)| d <= m.len().div_ceil(3))
        .min_by_key(|&(d, _)| d)
        .map(|(_, m)| m)
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

/// Parses a spec string into its [`Brdf`]; a relative `merl:` path is taken relative to `base`.
pub(super) fn parse(spec: &str, base: &Path) -> Result<Brdf, BrdfError> {
    let trimmed = spec.trim();
    let (model, rest) = match trimmed.split_once(':') {
        Some((m, r)) => (m.trim().to_ascii_lowercase(), r),
        None => (trimmed.to_ascii_lowercase(), ""),
    };
    if model == "merl" {
        let path = rest.trim();
        if path.is_empty() {
            let reason = "merl needs a file: merl:path/to/material.binary".into();
            return Err(SpecError { spec: spec.to_string(), reason }.into());
        }
        return Ok(Brdf::Merl(Arc::new(MerlBrdf::read(&base.join(path))?)));
    }
    Ok(parse_analytic(spec, model, rest)?)
}

/// An analytic model `model` with its parameter text `rest` (after the colon).
fn parse_analytic(spec: &str, model: String, rest: &str) -> Result<Brdf, SpecError> {
    let err = |reason: String| SpecError { spec: spec.to_string(), reason };
    let params = parse_params(rest, spec)?;
    let mut p = Params { spec, model: model.clone(), params, used: vec![] };
    p.check_known()?;
    let parsed = match model.as_str() {
        "lambert" => {
            let albedo = p.optional("albedo", 1.0)?;
            if !(0.0..=1.0).contains(&albedo) {
                return Err(err(format!("lambert albedo must be in [0, 1], got {albedo}")));
            }
            Brdf::Lambert(Lambert { albedo })
        }
        "phong" => {
            let s = p.positive("s")?;
            p.peak("the lobe's peak (s+1)/(2π)", (s + 1.0) / (2.0 * PI), "s <=", 2.0 * PI * MAX_BRDF_PEAK - 1.0)?;
            Brdf::Phong(Phong { exponent: s })
        }
        "blinn-phong" => {
            let s = p.positive("s")?;
            p.peak("the lobe's peak (s+2)/(8π)", (s + 2.0) / (8.0 * PI), "s <=", 8.0 * PI * MAX_BRDF_PEAK - 2.0)?;
            Brdf::BlinnPhong(BlinnPhong { exponent: s })
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
            Brdf::TorranceSparrow(TorranceSparrow { sigma })
        }
        "kajiya-kay" => {
            let s = p.positive("s")?;
            p.peak("the lobe's peak (s+1)/(2π)", (s + 1.0) / (2.0 * PI), "s <=", 2.0 * PI * MAX_BRDF_PEAK - 1.0)?;
            Brdf::KajiyaKay(KajiyaKay { exponent: s })
        }
        "ggx" => {
            let r = p.positive("roughness")?;
            Brdf::Ggx(p.ggx_layer(r)?)
        }
        "gltf" => {
            // glTF's own defaults: baseColorFactor 1, metallicFactor 1, roughnessFactor 1.
            let base = p.colour("base", [1.0; 3])?;
            let metalness = p.optional("metalness", 1.0)?;
            if !(0.0..=1.0).contains(&metalness) {
                return Err(err(format!("gltf metalness must be in [0, 1], got {metalness}")));
            }
            let roughness = p.optional("roughness", 1.0)?;
            let specular = p.ggx_layer(roughness)?;
            Brdf::Gltf(GltfMaterial { base, metalness, specular })
        }
        "lafortune" => {
            let kd = p.optional("kd", 0.0)?;
            if kd < 0.0 {
                return Err(err(format!("lafortune kd must be >= 0, got {kd}")));
            }
            p.peak("the diffuse term kd/π", kd / PI, "kd <=", PI * MAX_BRDF_PEAK)?;
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
            Brdf::Lafortune(Lafortune { kd, lobes })
        }
        "" => return Err(err(format!("empty model name; accepted: {ACCEPTED}"))),
        other => {
            let hint = did_you_mean(other).map(|m| format!(" (did you mean {m:?}?)")).unwrap_or_default();
            return Err(err(format!("unknown BRDF model {other:?}{hint}; accepted: {ACCEPTED}")));
        }
    };
    p.finish()?;
    Ok(parsed)
}

/// The canonical spec string (parses back to the same BRDF).
impl fmt::Display for Brdf {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Brdf::Lambert(m) if m.albedo == 1.0 => write!(f, "lambert"),
            Brdf::Lambert(m) => write!(f, "lambert:albedo={}", m.albedo),
            Brdf::Phong(m) => write!(f, "phong:s={}", m.exponent),
            Brdf::BlinnPhong(m) => write!(f, "blinn-phong:s={}", m.exponent),
            Brdf::TorranceSparrow(m) => write!(f, "torrance-sparrow:sigma={}", m.sigma),
            Brdf::KajiyaKay(m) => write!(f, "kajiya-kay:s={}", m.exponent),
            Brdf::Lafortune(m) => {
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
            Brdf::Ggx(m) => write!(f, "ggx:roughness={}", m.roughness()),
            Brdf::Gltf(m) => {
                let [r, g, b] = m.base;
                write!(f, "gltf:base={r}/{g}/{b},metalness={},roughness={}", m.metalness, m.specular.roughness())
            }
            Brdf::Merl(m) => write!(f, "merl:{}", m.path().display()),
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
            "ggx" => "roughness (perceptual roughness in (0, 1], alpha = roughness^2)",
            "gltf" => "base (R/G/B or one grey value, each in [0, 1], default 1), metalness (in [0, 1], default 1), roughness (in (0, 1], default 1)",
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
            "ggx" => &["roughness"],
            "gltf" => &["base", "metalness", "roughness"],
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

    /// The text of parameter `key`, if given (at most once).
    fn text(&mut self, key: &str) -> Result<Option<String>, SpecError> {
        let hits: Vec<String> = self.params.iter().filter(|(k, _)| k == key).map(|(_, v)| v.clone()).collect();
        if hits.len() > 1 {
            return Err(self.err(format!("parameter {key} is given {} times", hits.len())));
        }
        self.used.push(key.to_string());
        Ok(hits.into_iter().next())
    }

    fn single(&mut self, key: &str) -> Result<Option<f64>, SpecError> {
        self.text(key)?.map(|v| self.number(key, &v)).transpose()
    }

    fn optional(&mut self, key: &str, default: f64) -> Result<f64, SpecError> {
        Ok(self.single(key)?.unwrap_or(default))
    }

    /// Refuses parameters whose BRDF peak exceeds [`MAX_BRDF_PEAK`] (`docs/limits.md`):
    /// `key` and `limit` say the bound on the parameter it amounts to (e.g. "s <=", 6.3e8).
    fn peak(&self, what: &str, peak: f64, key: &str, limit: f64) -> Result<(), SpecError> {
        if peak > MAX_BRDF_PEAK {
            return Err(self.err(format!(
                "{what} = {peak:.3e} is above the ceiling of {MAX_BRDF_PEAK:e} sr^-1 ({key} {limit:.3e}; \
                 no stage resolves a narrower lobe, see docs/limits.md)"
            )));
        }
        Ok(())
    }

    /// The GGX layer of perceptual roughness `r` (`ggx`, and `gltf`'s specular): r in (0, 1], its
    /// normal-incidence peak 1/(4πα²) within [`MAX_BRDF_PEAK`] (r = 0, the mirror, is a delta).
    fn ggx_layer(&self, r: f64) -> Result<GgxMicrofacet, SpecError> {
        if !(r > 0.0 && r <= 1.0) {
            return Err(self.err(format!("{} roughness must be in (0, 1], got {r}", self.model)));
        }
        let min_r = (4.0 * PI * MAX_BRDF_PEAK).powf(-0.25);
        let peak = GgxMicrofacet::normal_peak(r);
        self.peak("the peak at normal incidence 1/(4πα²), α = r²", peak, "roughness >=", min_r)?;
        GgxMicrofacet::new(r).map_err(|e| self.err(e.to_string()))
    }

    /// A colour `key=R/G/B` (or one grey value), each component in [0, 1].
    fn colour(&mut self, key: &str, default: [f64; 3]) -> Result<[f64; 3], SpecError> {
        let Some(v) = self.text(key)? else { return Ok(default) };
        let nums = v.split('/').map(|x| self.number(key, x.trim())).collect::<Result<Vec<f64>, _>>()?;
        let rgb = match nums.as_slice() {
            [g] => [*g; 3],
            [r, g, b] => [*r, *g, *b],
            _ => return Err(self.err(format!("{key}={v:?} needs R/G/B or one grey value, got {} numbers", nums.len()))),
        };
        if rgb.iter().any(|c| !(0.0..=1.0).contains(c)) {
            return Err(self.err(format!("{key}={v} must have every component in [0, 1]")));
        }
        Ok(rgb)
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
            "ggx:roughness=0.5",
            "ggx:roughness=1",
        ] {
            let spec = Brdf::parse(s).unwrap().spec();
            assert_eq!(Brdf::parse(&spec).unwrap().spec(), spec, "{s}");
        }
        assert_eq!(Brdf::parse(" Phong : s = 30 ").unwrap().spec(), "phong:s=30");
        assert_eq!(Brdf::parse("GGX: Roughness = 0.25").unwrap().spec(), "ggx:roughness=0.25");
    }

    #[test]
    fn errors_say_what_is_wrong_and_what_is_accepted() {
        let e = |s: &str| Brdf::parse(s).unwrap_err().to_string();
        assert!(e("glossy:s=3").contains("unknown BRDF model \"glossy\";") && e("glossy").contains("phong:s=S"));
        assert!(e("torance-sparrow:sigma=0.2").contains("(did you mean \"torrance-sparrow\"?)"));
        assert!(e("phog:s=3").contains("(did you mean \"phong\"?)"));
        assert!(e("gg:roughness=0.5").contains("(did you mean \"ggx\"?)"));
        assert!(e("glossy").contains("ggx:roughness=R"));
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
        assert!(e("ggx").contains("ggx needs roughness"));
        assert!(e("ggx:roughness=0").contains("roughness must be > 0"));
        assert!(e("ggx:roughness=1.5").contains("in (0, 1]"));
        assert!(e("ggx:alpha=0.2").contains("does not take parameter \"alpha\""));
        // Ceilings (docs/limits.md): a lobe too tall for f64 energy sums, or too flat to matter.
        assert!(e("phong:s=1e308").contains("above the ceiling of 1e8"), "{}", e("phong:s=1e308"));
        assert!(e("blinn-phong:s=1e10").contains("ceiling"));
        assert!(e("kajiya-kay:s=1e300").contains("ceiling"));
        assert!(e("torrance-sparrow:sigma=1e-300").contains("sigma >="));
        assert!(e("torrance-sparrow:sigma=1e200").contains("ceiling of 100"));
        assert!(e("lafortune:kd=1e300,lobe=-1/1/2").contains("kd/π"));
        assert!(e("lafortune:lobe=-2/2/1e9").contains("(max |C|)^n"));
        // GGX: 1/(4πα²) ≤ 10⁸ holds for r ≥ (4π·10⁸)^(-1/4) ≈ 5.3e-3.
        assert!(e("ggx:roughness=1e-3").contains("roughness >= 5.3"), "{}", e("ggx:roughness=1e-3"));
        for ok in [
            "phong:s=1e8",
            "blinn-phong:s=1e8",
            "torrance-sparrow:sigma=1e-4",
            "lafortune:lobe=-0.5/0.5/1e12",
            "ggx:roughness=6e-3",
        ] {
            assert!(Brdf::parse(ok).is_ok(), "{ok}");
        }
    }

    #[test]
    fn merl_paths_are_read_relative_to_the_base() {
        let e = parse("merl:no-such.binary", Path::new("/nonexistent/dir")).unwrap_err().to_string();
        assert!(e.contains("/nonexistent/dir/no-such.binary") && e.contains("cannot read"), "{e}");
    }
}
