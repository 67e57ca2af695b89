//! Shading from a spherical harmonic reflection map (Ramamoorthi & Hanrahan 2002 §4, §7.5).
//!
//! - A **global** SHRM (eq. 7–8) is for a distant viewer: one reflection map per frame,
//!   B̃(R) = Σ_pq B̃_pq(R) Y_pq(v) for the camera's view direction v (eq. 12), then per pixel a
//!   bilinear lookup at R = reflect(v, n) — the real-time path of §7.5.
//! - A **local** SHRM is evaluated per pixel with that pixel's own view direction (eq. 6):
//!   B = Σ_pq B_pq(R) Y_pq(ω_o'), ω_o' the view in the texel frame R_z(β)·R_y(α) of R.
//! - Lambert SHRMs (`parameterization: normal`) are indexed by n and view-independent.

use super::{Hit, Shade};
use crate::io::document::{read_document, read_named_layers, BundleError};
use crate::io::RgbImage;
use crate::prefilter::document::{layer_name, ShrmBody, FORMAT, VERSION};
use crate::prefilter::shrm::{reflection_map, Shrm};
use crate::sh::basis::eval_basis_dir;
use crate::sh::legendre::LegendreTable;
use crate::sh::{count, index};
use crate::sphere::{self, LatLong};
use glam::{DMat3, DVec3};
use std::path::Path;

/// Errors of reading an SHRM: the document/EXR pair's errors.
pub type ShrmLoadError = BundleError;

/// Reads a `prtkit.shrm` document and the SHRM EXR it names (relative to the document's
/// directory when not absolute), checking layout, layer names and grid size.
pub fn load(doc_path: &Path) -> Result<(Shrm, ShrmBody), ShrmLoadError> {
    crate::io::read::refuse_stdin(doc_path, "an SHRM document")?;
    let body = read_document::<ShrmBody>(doc_path, FORMAT, VERSION)?.body;
    let bad = |reason: String| ShrmLoadError::Document { path: doc_path.into(), reason };
    if body.layout != "latlong" {
        return Err(bad(format!(
            "the SHRM uses the {} layout; render reads lat-long SHRMs (run prefilter with --output-layout latlong)",
            body.layout
        )));
    }
    if body.parameterization != "reflection" && body.parameterization != "normal" {
        return Err(bad(format!("unknown parameterization {:?}", body.parameterization)));
    }
    let file = body.shrm_file.clone().ok_or_else(|| bad("the document names no shrm_file".into()))?;
    let (exr, layers) = read_named_layers(doc_path, &file, "SHRM file")?;
    let mismatch = |reason: String| ShrmLoadError::Mismatch { exr: exr.clone(), doc: doc_path.into(), reason };
    let n = count(body.p_b);
    let mut ordered = Vec::with_capacity(n);
    for p in 0..=body.p_b {
        for q in -(p as isize)..=(p as isize) {
            let name = layer_name(p, q);
            let img = layers
                .iter()
                .find(|(l, _)| *l == name)
                .map(|(_, i)| i.clone())
                .ok_or_else(|| mismatch(format!("no layer {name} (P_B = {})", body.p_b)))?;
            if img.width != body.width || img.height != body.height {
                return Err(mismatch(format!(
                    "layer {name} is {}x{}, the document says {}x{}",
                    img.width, img.height, body.width, body.height
                )));
            }
            ordered.push(img);
        }
    }
    if ordered.iter().flat_map(|i| &i.pixels).flatten().any(|v| !v.is_finite()) {
        return Err(mismatch("non-finite coefficients".into()));
    }
    Ok((Shrm { f_b: body.f_b, p_b: body.p_b, global: body.global, layers: ordered }, body))
}

fn sample(img: &RgbImage, taps: &[(usize, f64); 4]) -> [f64; 3] {
    let mut out = [0.0; 3];
    for &(i, wt) in taps {
        let v = img.pixels[i];
        for c in 0..3 {
            out[c] += wt * v[c] as f64;
        }
    }
    out
}

/// The SHRM shader.
pub struct ShrmShader {
    shrm: Shrm,
    by_normal: bool,
    /// For a global SHRM: the reflection map of the frame's view direction (eq. 12).
    frame_map: Option<RgbImage>,
    table: LegendreTable,
}

impl ShrmShader {
    /// Prepares shading. For a global SHRM, `view` (unit, towards the distant viewer) selects
    /// the frame's reflection map — the per-frame cost of §7.5, Σ over (P_B+1)² layers per texel.
    pub fn new(shrm: Shrm, by_normal: bool, view: DVec3) -> Self {
        let frame_map = (shrm.global || shrm.p_b == 0).then(|| reflection_map(&shrm, view));
        let table = LegendreTable::new(shrm.p_b);
        ShrmShader { shrm, by_normal, frame_map, table }
    }
}

impl Shade for ShrmShader {
    fn shade(&self, hit: &Hit, wo: DVec3) -> [f64; 3] {
        let key = if self.by_normal { hit.n } else { super::reflect(wo, hit.n) };
        let (w, h) = (self.shrm.width(), self.shrm.height());
        let taps = LatLong::new(w, h).taps(key);
        if let Some(map) = &self.frame_map {
            return sample(map, &taps);
        }
        // Local SHRM, eq. 6: the view in the frame R_z(β)R_y(α) of the continuous (α, β) of R.
        let frame: DMat3 = sphere::frame_of(key);
        let mut y = vec![0.0; count(self.shrm.p_b)];
        eval_basis_dir(&self.table, frame.transpose() * wo, &mut y);
        let mut out = [0.0; 3];
        for p in 0..=self.shrm.p_b {
            for q in -(p as isize)..=(p as isize) {
                let i = index(p, q);
                let v = sample(&self.shrm.layers[i], &taps);
                for c in 0..3 {
                    out[c] += y[i] * v[c];
                }
            }
        }
        out
    }
}
