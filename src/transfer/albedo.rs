//! The albedo a diffuse bake folds into its transfer: one grey ρ, one colour, or each vertex's
//! base colour as the mesh file gives it (glTF's base colour factor, texture and `COLOR_0`, a
//! PLY's vertex colours: [`crate::mesh::Mesh::load_coloured`]).
//!
//! Sloan, Kautz & Snyder 2002 relight each colour channel with its own lighting coefficients
//! (§4). With a grey albedo the three channels share one transfer vector; with a coloured one
//! each channel has its own, three per vertex: the direct part scales with the receiver's
//! albedo, T_c(x) = ρ_c(x) T(x) (eq. 7–8, ρ outside the integral), and a bounce carries the
//! channel's albedo at both ends, T^b_c(x) = (ρ_c(x)/N) Σ_k T^{b−1}_c(y_k) (eq. 9), so light
//! off a red wall reaches its neighbours red (colour bleeding). The rays do not depend on the
//! colour: they are traced once, with ρ = 1, and the channels are made from that one trace.

use crate::mesh::Mesh;

/// The albedo of a diffuse bake (`transfer --albedo`).
#[derive(Clone, Debug, PartialEq)]
pub enum Albedo {
    /// One grey ρ everywhere: one transfer vector per vertex, ρ folded in.
    Grey(f64),
    /// One linear RGB colour everywhere: three transfer vectors per vertex.
    Colour([f64; 3]),
    /// Each vertex's linear RGB base colour from the mesh file: three transfer vectors per
    /// vertex.
    Mesh,
}

impl Default for Albedo {
    fn default() -> Self {
        Albedo::Grey(1.0)
    }
}

impl Albedo {
    /// Parses `--albedo`: a number (grey), three numbers `R,G,B` (a linear colour), or `mesh`.
    pub fn parse(s: &str) -> Result<Albedo, String> {
        if s.trim().eq_ignore_ascii_case("mesh") {
            return Ok(Albedo::Mesh);
        }
        let numbers: Result<Vec<f64>, _> = s.split(',').map(|x| x.trim().parse::<f64>()).collect();
        match numbers.as_deref() {
            Ok(&[grey]) => Ok(Albedo::Grey(grey)),
            Ok(&[r, g, b]) => Ok(Albedo::Colour([r, g, b])),
            _ => Err(format!(
                "{s:?}: an albedo is a number (grey, e.g. 0.8), three numbers R,G,B (linear, e.g. 0.8,0.2,0.1) or \
                 `mesh` (each vertex's base colour from the mesh file)"
            )),
        }
    }

    /// Transfer vectors per vertex: 1 for a grey albedo, 3 (R, G, B) for a coloured one.
    pub fn channels(&self) -> usize {
        match self {
            Albedo::Grey(_) => 1,
            Albedo::Colour(_) | Albedo::Mesh => 3,
        }
    }

    /// The ρ the integrators fold in: the grey albedo, or 1 for a coloured bake, whose channels
    /// are scaled afterwards ([`colourize`]).
    pub fn folded(&self) -> f64 {
        match self {
            Albedo::Grey(a) => *a,
            Albedo::Colour(_) | Albedo::Mesh => 1.0,
        }
    }

    /// The first component that is not a finite number ≥ 0, if any.
    pub fn invalid(&self) -> Option<f64> {
        let bad = |a: f64| !(a.is_finite() && a >= 0.0);
        match self {
            Albedo::Grey(a) => bad(*a).then_some(*a),
            Albedo::Colour(c) => c.iter().copied().find(|&a| bad(a)),
            Albedo::Mesh => None,
        }
    }

    /// Each vertex's (ρ_r, ρ_g, ρ_b) on `mesh` for a coloured bake; `None` for a grey one, or
    /// when the albedo is the mesh's and it holds no colours (the stage refuses that first).
    pub fn colours(&self, mesh: &Mesh) -> Option<Vec<[f64; 3]>> {
        match self {
            Albedo::Grey(_) => None,
            Albedo::Colour(c) => Some(vec![*c; mesh.positions.len()]),
            Albedo::Mesh => mesh.base_colors.clone(),
        }
    }

    /// How the manifest and the `.glb`'s extras state it: the number, `[r, g, b]`, or for the
    /// mesh's colours where they come from and their range.
    pub fn describe(&self, colours: Option<&[[f64; 3]]>) -> serde_json::Value {
        match (self, colours) {
            (Albedo::Grey(a), _) => serde_json::json!(a),
            (Albedo::Colour(c), _) => serde_json::json!(c),
            (Albedo::Mesh, colours) => {
                let colours = colours.unwrap_or_default();
                let fold = |f: fn(f64, f64) -> f64, start: f64| {
                    (0..3).map(|c| colours.iter().map(|v| v[c]).fold(start, f)).collect::<Vec<f64>>()
                };
                let count = colours.len().max(1) as f64;
                let mean: Vec<f64> = (0..3).map(|c| colours.iter().map(|v| v[c]).sum::<f64>() / count).collect();
                serde_json::json!({
                    "source": "mesh",
                    "description": "each vertex's linear RGB base colour as the mesh file gives it \
                                    (docs/formats/mesh-colours.md)",
                    "min": fold(f64::min, f64::INFINITY),
                    "max": fold(f64::max, f64::NEG_INFINITY),
                    "mean": mean,
                })
            }
        }
    }
}

/// The transfer of a coloured bake from its grey one at ρ = 1: `grey` holds `coeffs` values
/// per vertex, the result 3·`coeffs`, channel-major (value c·coeffs + i is channel c's
/// coefficient i), channel c scaled by the vertex's ρ_c.
pub fn colourize(grey: &[f64], coeffs: usize, colours: &[[f64; 3]]) -> Vec<f64> {
    let mut out = Vec::with_capacity(grey.len() * 3);
    for (t, rho) in grey.chunks_exact(coeffs).zip(colours) {
        for r in rho {
            out.extend(t.iter().map(|x| r * x));
        }
    }
    out
}

/// The albedo a bounce reflects with at the vertex (or texel) that gathers (eq. 9's ρ).
#[derive(Clone, Copy, Debug)]
pub enum Reflectance<'a> {
    /// One grey ρ: n² values per vertex.
    Grey(f64),
    /// Each vertex's (ρ_r, ρ_g, ρ_b): 3·n² values per vertex, channel-major.
    Rgb(&'a [[f64; 3]]),
}

impl Reflectance<'_> {
    /// Blocks of n² values per vertex: 1 or 3.
    pub fn channels(&self) -> usize {
        match self {
            Reflectance::Grey(_) => 1,
            Reflectance::Rgb(_) => 3,
        }
    }

    /// Vertex `v`'s ρ of block `c`.
    pub fn at(&self, v: usize, c: usize) -> f64 {
        match self {
            Reflectance::Grey(a) => *a,
            Reflectance::Rgb(colours) => colours[v][c],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn albedos_parse_as_documented() {
        assert_eq!(Albedo::parse("0.8"), Ok(Albedo::Grey(0.8)));
        assert_eq!(Albedo::parse("0.8, 0.2,0.1"), Ok(Albedo::Colour([0.8, 0.2, 0.1])));
        assert_eq!(Albedo::parse("Mesh"), Ok(Albedo::Mesh));
        for bad in ["", "0.5,0.5", "red", "1,2,3,4"] {
            assert!(Albedo::parse(bad).is_err(), "{bad}");
        }
        assert_eq!(Albedo::Colour([0.5, -1.0, 0.2]).invalid(), Some(-1.0));
        assert!(Albedo::Grey(f64::NAN).invalid().is_some_and(f64::is_nan));
        assert_eq!(Albedo::Colour([0.5, 0.0, 0.2]).invalid(), None);
    }

    #[test]
    fn colourize_scales_each_channel_by_its_albedo() {
        let grey = [1.0, 2.0, 3.0, 4.0];
        let out = colourize(&grey, 2, &[[0.5, 1.0, 0.0], [2.0, 0.25, 1.0]]);
        assert_eq!(out, vec![0.5, 1.0, 1.0, 2.0, 0.0, 0.0, 6.0, 8.0, 0.75, 1.0, 3.0, 4.0]);
    }
}
