//! Relighting from a `transfer` bake (Sloan, Kautz & Snyder 2002, §4's run-time: "the dot
//! product of the lighting's and the vertex's transfer vectors"): per vertex,
//! B(x) = Σ_i T_i(x) L_i with L_i the environment's SH in the mesh's axes, then interpolated over
//! each triangle by the hit's barycentrics, as a vertex shader's output is.
//!
//! **A turning environment.** The transfer is in the mesh's axes; an environment turned by R is
//! L'(ω) = L(R⁻¹ω), whose coefficients are the block-diagonal SH rotation of L's
//! ([`crate::sh::rotate::ShRotation`], Ivanic & Ruedenberg 1996): one small matrix per frame, the
//! transfer untouched. [`relight`] is that frame: rotation, then one dot product per vertex.
//!
//! The bake is read from its `.glb` (`docs/formats/transfer.md`), the file an engine loads: its
//! `POSITION` and `_PRT_k` attributes and the `prtkit.transfer` extras (order, mode, albedo).

use super::{Hit, Shade};
use crate::io::glb;
use crate::mesh::Mesh;
use crate::sh::rotate::ShRotation;
use crate::sh::ShCoeffs;
use glam::{DMat3, DVec3};
use serde_json::Value;

/// A transfer bake read back from its `.glb`.
#[derive(Clone, Debug)]
pub struct TransferBake {
    /// The file, for messages.
    pub name: String,
    /// SH order n (bands 0..n−1).
    pub order: usize,
    /// `unshadowed`, `shadowed` or `interreflected`.
    pub mode: String,
    /// The grey albedo baked in; `None` for a coloured bake (`transfer --albedo R,G,B` or
    /// `mesh`), whose colour is in its three transfer vectors.
    pub albedo: Option<f64>,
    /// Transfer vectors per vertex and term: 1, or 3 (R, G, B) for a coloured bake.
    pub channels: usize,
    /// Positions as stored (single precision).
    pub positions: Vec<[f32; 3]>,
    /// Triangles in the file.
    pub triangles: usize,
    /// n² coefficients per vertex (K·n², term-major, for glossy bakes; 3·n², channel-major, for
    /// coloured ones), vertex after vertex.
    pub transfer: Vec<f32>,
    /// What a glossy bake was factored with (absent for diffuse bakes).
    pub glossy: Option<GlossyBake>,
    /// The clustered PCA the transfer is stored in (then `transfer` is empty).
    pub compressed: Option<Compressed>,
}

/// A transfer stored by clustered PCA (Sloan et al. 2003, eq. 2): T(x) = m_c + Σ_p w_p b_cp.
#[derive(Clone, Debug)]
pub struct Compressed {
    /// Clusters C.
    pub clusters: usize,
    /// Directions per cluster P.
    pub components: usize,
    /// m_c (C × D, D the values per vertex).
    pub means: Vec<f32>,
    /// b_cp (C × P × D).
    pub bases: Vec<f32>,
    /// Each vertex's cluster.
    pub cluster_of: Vec<u32>,
    /// Each vertex's P weights.
    pub weights: Vec<f32>,
}

/// The factorization a glossy bake records (the `.glb` extras' `glossy`), checked against the
/// factors `render --factors` reads to evaluate h_k.
#[derive(Clone, Debug, serde::Deserialize)]
pub struct GlossyBake {
    /// Terms K.
    pub terms: usize,
    /// The factored BRDF's spec.
    pub brdf: String,
    /// The factor document the bake read.
    pub factors: String,
    /// The factors' grid.
    pub domain: crate::factor::Domain,
    /// Its bins n.
    pub resolution: usize,
    /// Whether the factors hold the cosine.
    pub cosine: bool,
    /// σ_0 … σ_{K−1}, folded into the transfer.
    pub singular_values: Vec<f64>,
    /// The normal's frame the bake is in ([`crate::transfer::glossy::FRAME`]; absent in bakes
    /// of the earlier frame R_z(φ_n)·R_y(θ_n)).
    #[serde(default)]
    pub frame: Option<String>,
    /// h_0 … h_{K−1} on the grid, n² values each (the `.glb`'s `glossy.h` blob).
    #[serde(skip)]
    pub h: Vec<Vec<f64>>,
}

impl GlossyBake {
    /// The factor grid h_k is sampled on.
    pub fn grid(&self) -> crate::factor::Grid {
        crate::factor::Grid { n: self.resolution, domain: self.domain }
    }

    /// Whether `f` (read from `factors_name`) is the factorization the bake `bake` was made with:
    /// the same grid and the same leading singular values.
    pub fn check_factors(
        &self,
        bake: &str,
        f: &crate::factor::Factorization,
        factors_name: &str,
    ) -> Result<(), OtherFactors> {
        let (bake, factors) = (bake.to_string(), factors_name.to_string());
        if f.grid.n != self.resolution || f.grid.domain != self.domain {
            return Err(OtherFactors::Grid {
                bake,
                domain: self.domain,
                resolution: self.resolution,
                baked_from: self.factors.clone(),
                factors,
                other_domain: f.grid.domain,
                other_resolution: f.grid.n,
            });
        }
        if f.h.len() < self.terms {
            return Err(OtherFactors::Terms { bake, terms: self.terms, factors, held: f.h.len() });
        }
        let same = self
            .singular_values
            .iter()
            .zip(&f.singular_values)
            .all(|(a, b)| (a - b).abs() <= 1e-9 * a.abs().max(1e-300));
        if !same {
            return Err(OtherFactors::SingularValues {
                bake,
                baked_from: self.factors.clone(),
                baked_sigma: self.singular_values.first().copied().unwrap_or(0.0),
                factors,
                sigma: f.singular_values.first().copied().unwrap_or(0.0),
            });
        }
        Ok(())
    }
}

/// A factorization that is not the one a glossy bake was made with.
#[derive(Debug, thiserror::Error)]
pub enum OtherFactors {
    /// Another grid.
    #[error("{bake} was baked on a {domain} grid of {resolution} bins ({baked_from}); {factors} is a {other_domain} grid of {other_resolution}")]
    Grid {
        /// The bake's file.
        bake: String,
        /// The bake's grid.
        domain: crate::factor::Domain,
        /// Its bins n.
        resolution: usize,
        /// The factor document the bake read.
        baked_from: String,
        /// The factor document given.
        factors: String,
        /// Its grid.
        other_domain: crate::factor::Domain,
        /// Its bins n.
        other_resolution: usize,
    },
    /// Fewer terms than the bake has.
    #[error("{bake} has {terms} terms; {factors} holds {held}")]
    Terms {
        /// The bake's file.
        bake: String,
        /// Its terms K.
        terms: usize,
        /// The factor document given.
        factors: String,
        /// Its terms.
        held: usize,
    },
    /// Other singular values: another factorization on the same grid.
    #[error("{bake} was baked from {baked_from} (σ_0 = {baked_sigma:.6e}); {factors} is another factorization (σ_0 = {sigma:.6e})")]
    SingularValues {
        /// The bake's file.
        bake: String,
        /// The factor document the bake read.
        baked_from: String,
        /// Its σ_0.
        baked_sigma: f64,
        /// The factor document given.
        factors: String,
        /// Its σ_0.
        sigma: f64,
    },
}

/// A transfer bake of another mesh than the one given.
#[derive(Debug, thiserror::Error)]
pub enum OtherMesh {
    /// Other vertex or triangle counts.
    #[error("{bake}: the transfer is of a mesh of {bake_vertices} vertices and {bake_triangles} triangles, the mesh has {vertices} and {triangles}")]
    Size {
        /// The bake's file.
        bake: String,
        /// Its vertices.
        bake_vertices: usize,
        /// Its triangles.
        bake_triangles: usize,
        /// The mesh's vertices.
        vertices: usize,
        /// The mesh's triangles.
        triangles: usize,
    },
    /// A vertex elsewhere.
    #[error("{bake}: vertex {vertex} is not where the mesh has it: the transfer is of another mesh")]
    Vertex {
        /// The bake's file.
        bake: String,
        /// The first vertex that differs.
        vertex: usize,
    },
}

/// A glossy bake in another normal's frame than [`crate::transfer::glossy::FRAME`]: its c_k and
/// h_k would be read in the wrong frame and relit wrong.
#[derive(Debug, thiserror::Error)]
#[error(
    "{file}: a glossy bake in the normal's frame {}, not {}: made by an earlier prtkit; bake it again",
    frame.as_deref().unwrap_or("Rz(phi_n) Ry(theta_n) (extras.prtkit.transfer.glossy names no frame)"),
    crate::transfer::glossy::FRAME
)]
pub struct OtherFrame {
    /// The file.
    pub file: String,
    /// The frame it names, if any.
    pub frame: Option<String>,
}

/// Why a `.glb` cannot be relit.
#[derive(Debug, thiserror::Error)]
pub enum ReadBakeError {
    /// Not a transfer bake, or a damaged one.
    #[error(transparent)]
    NotATransfer(#[from] NotATransfer),
    /// A glossy bake of another frame.
    #[error(transparent)]
    OtherFrame(#[from] OtherFrame),
}

/// A `.glb` that is not a transfer bake `render` can read.
#[derive(Debug, thiserror::Error)]
#[error("{file}: not a prtkit transfer .glb: {reason}")]
pub struct NotATransfer {
    /// The file.
    pub file: String,
    /// What is wrong or missing.
    pub reason: String,
}

/// A `.glb`'s JSON and BIN chunks, read with every fault naming the file.
struct Glb<'a> {
    name: &'a str,
    gltf: Value,
    bin: &'a [u8],
}

impl<'a> Glb<'a> {
    fn bad(&self, reason: impl Into<String>) -> NotATransfer {
        NotATransfer { file: self.name.to_string(), reason: reason.into() }
    }

    /// The accessor of attribute `name` in `attributes`, of `kind` (SCALAR, VEC3, VEC4) and
    /// component type `storage`: its count and its bytes.
    fn accessor(
        &self,
        attributes: &Value,
        name: &str,
        kind: &str,
        storage: Storage,
    ) -> Result<(usize, &'a [u8]), NotATransfer> {
        let index = attributes[name].as_u64().ok_or_else(|| self.bad(format!("no {name} attribute")))?;
        let a = &self.gltf["accessors"][index as usize];
        let component_type = a["componentType"].as_u64();
        let normalized = a["normalized"].as_bool().unwrap_or(false);
        if component_type != Some(storage.component_type() as u64)
            || normalized != (storage != Storage::Float)
            || a["type"].as_str() != Some(kind)
        {
            return Err(self.bad(format!(
                "{name} is a {} accessor of componentType {}{}, not {} {kind}",
                a["type"].as_str().unwrap_or("?"),
                component_type.map_or("none".into(), |c| c.to_string()),
                if normalized { " (normalized)" } else { "" },
                storage.describe()
            )));
        }
        let count = a["count"].as_u64().ok_or_else(|| self.bad("an accessor has no count"))? as usize;
        let view = a["bufferView"].as_u64().ok_or_else(|| self.bad("no bufferView"))?;
        let view = &self.gltf["bufferViews"][view as usize];
        let start = view["byteOffset"].as_u64().unwrap_or(0) as usize + a["byteOffset"].as_u64().unwrap_or(0) as usize;
        let components = match kind {
            "SCALAR" => 1,
            "VEC3" => 3,
            _ => 4,
        };
        let data = count
            .checked_mul(storage.bytes() * components)
            .and_then(|length| start.checked_add(length))
            .and_then(|end| self.bin.get(start..end))
            .ok_or_else(|| self.bad("an accessor runs past the BIN chunk"))?;
        Ok((count, data))
    }

    /// `per_vertex` values for each of `vertices`, packed four to a VEC4 attribute PREFIX0,
    /// PREFIX1, … of `attributes`, stored as `storage` (normalized integers read as glTF 2.0
    /// §3.11 says, max(c / q, −1), before any scale).
    fn vec4s(
        &self,
        attributes: &Value,
        prefix: &str,
        vertices: usize,
        per_vertex: usize,
        storage: Storage,
    ) -> Result<Vec<f32>, NotATransfer> {
        crate::limits::check_memory("the transfer", (vertices as u128) * (per_vertex as u128) * 4)
            .map_err(|e| self.bad(e.to_string()))?;
        let mut out = vec![0.0f32; vertices * per_vertex];
        for k in 0..per_vertex.div_ceil(4) {
            let name = format!("{prefix}{k}");
            let (count, data) = self.accessor(attributes, &name, "VEC4", storage)?;
            if count != vertices {
                return Err(self.bad(format!("{prefix}{k} has {count} vertices, POSITION {vertices}")));
            }
            for (v, c) in storage.read(data).chunks_exact(4).enumerate() {
                for j in 0..4 {
                    if 4 * k + j < per_vertex {
                        out[v * per_vertex + 4 * k + j] = c[j];
                    }
                }
            }
        }
        if out.iter().any(|t| !t.is_finite()) {
            return Err(self.bad(format!("a value of {prefix}k is not finite")));
        }
        Ok(out)
    }

    /// The uncompressed transfer, `coeffs` values per vertex: `_PRT_k` times the value index's
    /// scale when quantized (docs/formats/transfer.md).
    fn transfer(
        &self,
        attributes: &Value,
        vertices: usize,
        coeffs: usize,
        quantized: &Quantized,
    ) -> Result<Vec<f32>, NotATransfer> {
        let mut transfer = self.vec4s(attributes, "_PRT_", vertices, coeffs, quantized.storage)?;
        if let Some(scales) = &quantized.scales {
            if scales.len() != coeffs {
                return Err(self.bad(format!("{} holds {} scales for {coeffs} values", quantized.blob, scales.len())));
            }
            for row in transfer.chunks_exact_mut(coeffs) {
                row.iter_mut().zip(scales).for_each(|(t, s)| *t *= s);
            }
        }
        Ok(transfer)
    }

    /// The blob `name` of the mesh's extras, `None` when absent.
    fn blob(&self, name: &str) -> Option<Result<Vec<f32>, NotATransfer>> {
        glb::blob(&self.gltf, self.bin, name).map(|read| read.map_err(|e| self.bad(e)))
    }

    /// A glossy bake's record and its h_k (the `glossy.h` blob), checked.
    fn glossy(&self, record: &Value) -> Result<GlossyBake, NotATransfer> {
        let mut g = serde_json::from_value::<GlossyBake>(record.clone())
            .map_err(|e| self.bad(format!("extras.prtkit.transfer.glossy: {e}")))?;
        let max_resolution = crate::limits::MAX_FACTOR_RESOLUTION;
        if !(1..=max_resolution.pow(2)).contains(&g.terms) || g.singular_values.len() != g.terms {
            return Err(self.bad(format!("glossy terms {} with {} singular values", g.terms, g.singular_values.len())));
        }
        if !(2..=max_resolution).contains(&g.resolution) {
            return Err(self.bad(format!("glossy resolution {} is outside 2..={max_resolution}", g.resolution)));
        }
        let cells = g.resolution * g.resolution;
        let h = self
            .blob(crate::transfer::stage::GLOSSY_H_BLOB)
            .ok_or_else(|| self.bad("a glossy transfer without its glossy.h blob"))??;
        if h.len() != g.terms * cells || h.iter().any(|v| !v.is_finite()) {
            return Err(self.bad(format!(
                "glossy.h holds {} values, not {} finite ones ({} terms of {cells})",
                h.len(),
                g.terms * cells,
                g.terms
            )));
        }
        g.h = h.chunks_exact(cells).map(|t| t.iter().map(|&v| v as f64).collect()).collect();
        Ok(g)
    }

    /// The clustered PCA `record` describes, for `vertices` of `coeffs` values each.
    fn compressed(
        &self,
        record: &Value,
        attributes: &Value,
        vertices: usize,
        coeffs: usize,
        quantized: &Quantized,
    ) -> Result<Compressed, NotATransfer> {
        let clusters = record["clusters"].as_u64().unwrap_or(0) as usize;
        let components = record["components"].as_u64().unwrap_or(0) as usize;
        if !(1..=crate::limits::MAX_CPCA_CLUSTERS).contains(&clusters)
            || !(1..=crate::limits::MAX_CPCA_DIRECTIONS).contains(&components)
        {
            return Err(self.bad(format!("cpca: {clusters} clusters of {components} directions")));
        }
        let (count, data) = self.accessor(attributes, "_PRT_CLUSTER", "SCALAR", Storage::Float)?;
        let cluster_of = Storage::Float
            .read(data)
            .into_iter()
            .map(|c| (c >= 0.0 && c.fract() == 0.0 && (c as usize) < clusters).then_some(c as u32))
            .collect::<Option<Vec<u32>>>()
            .filter(|_| count == vertices)
            .ok_or_else(|| self.bad(format!("_PRT_CLUSTER must hold {vertices} cluster numbers below {clusters}")))?;
        let blob = |name: &str, len: usize| -> Result<Vec<f32>, NotATransfer> {
            let values = self.blob(name).ok_or_else(|| self.bad(format!("no {name} blob")))??;
            if values.len() != len || values.iter().any(|v| !v.is_finite()) {
                return Err(self.bad(format!("{name} holds {} values, not {len} finite ones", values.len())));
            }
            Ok(values)
        };
        let means = blob("cpca.means", clusters * coeffs)?;
        let bases = blob("cpca.bases", clusters * components * coeffs)?;
        let mut weights = self.vec4s(attributes, "_PRT_W_", vertices, components, quantized.storage)?;
        if let Some(scales) = &quantized.scales {
            if scales.len() != clusters {
                return Err(self.bad(format!(
                    "{} holds {} scales for {clusters} clusters",
                    quantized.blob,
                    scales.len()
                )));
            }
            // w_p = max(c / q, −1) × the cluster's scale (docs/formats/transfer.md).
            for (w, &c) in weights.chunks_exact_mut(components).zip(&cluster_of) {
                w.iter_mut().for_each(|x| *x *= scales[c as usize]);
            }
        }
        Ok(Compressed { clusters, components, means, bases, cluster_of, weights })
    }
}

/// The component type a bake's per-vertex values are stored as (`transfer --quantize`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Storage {
    /// FLOAT.
    Float,
    /// Normalized SHORT, read as max(c / 32767, −1).
    NormalizedShort,
    /// Normalized BYTE, read as max(c / 127, −1).
    NormalizedByte,
}

impl Storage {
    fn component_type(self) -> u32 {
        match self {
            Storage::Float => glb::FLOAT,
            Storage::NormalizedShort => glb::SHORT,
            Storage::NormalizedByte => glb::BYTE,
        }
    }

    fn bytes(self) -> usize {
        glb::component_bytes(self.component_type()).expect("a component type the writer has")
    }

    fn describe(self) -> &'static str {
        match self {
            Storage::Float => "float (5126)",
            Storage::NormalizedShort => "normalized SHORT (5122), as extras.prtkit.transfer.quantization says,",
            Storage::NormalizedByte => "normalized BYTE (5120), as extras.prtkit.transfer.quantization says,",
        }
    }

    /// The values as a glTF client reads them ([`glb::decode_values`]).
    fn read(self, data: &[u8]) -> Vec<f32> {
        glb::decode_values(self.component_type(), data).expect("a component type the writer has")
    }
}

/// A bake's quantization as its extras record it: the storage, and the scales (absent for
/// float storage) from the blob named there.
struct Quantized {
    storage: Storage,
    blob: String,
    scales: Option<Vec<f32>>,
}

impl Glb<'_> {
    /// The extras' `quantization` (absent: float storage), its scales read and checked.
    fn quantized(&self, record: Option<&Value>) -> Result<Quantized, NotATransfer> {
        let Some(record) = record else {
            return Ok(Quantized { storage: Storage::Float, blob: String::new(), scales: None });
        };
        let storage = match (record["type"].as_str(), record["code_max"].as_i64()) {
            (Some("i16"), Some(32767)) => Storage::NormalizedShort,
            (Some("i8"), Some(127)) => Storage::NormalizedByte,
            (kind, code_max) => {
                return Err(self
                    .bad(format!("quantization {kind:?} with code_max {code_max:?} is not i16 (32767) or i8 (127)")))
            }
        };
        let blob = record["scales"].as_str().ok_or_else(|| self.bad("quantization without its scales blob"))?;
        let scales = self.blob(blob).ok_or_else(|| self.bad(format!("no {blob} blob")))??;
        if scales.iter().any(|s| !(s.is_finite() && *s >= 0.0)) {
            return Err(self.bad(format!("{blob}: a scale is not a finite number >= 0")));
        }
        Ok(Quantized { storage, blob: blob.to_string(), scales: Some(scales) })
    }
}

impl TransferBake {
    /// Reads the `.glb` bytes of the file `name`. Every fault names the file.
    pub fn from_glb(name: &str, bytes: &[u8]) -> Result<TransferBake, ReadBakeError> {
        let bad = |why: &str| NotATransfer { file: name.to_string(), reason: why.to_string() };
        let gltf = glb::json_chunk(bytes).ok_or_else(|| bad("no glTF 2 header and JSON chunk"))?;
        let bin = glb::bin_chunk(bytes).ok_or_else(|| bad("no BIN chunk"))?;
        let glb = Glb { name, gltf, bin };
        let mesh = &glb.gltf["meshes"][0];
        let extras = &mesh["extras"]["prtkit.transfer"];
        let order = extras["order"].as_u64().ok_or_else(|| bad("no extras.prtkit.transfer.order"))? as usize;
        if !(1..=crate::limits::MAX_TRANSFER_ORDER).contains(&order) {
            return Err(bad(&format!("order {order} is outside 1..={}", crate::limits::MAX_TRANSFER_ORDER)).into());
        }
        let mode = extras["mode"].as_str().ok_or_else(|| bad("no extras.prtkit.transfer.mode"))?.to_string();
        let glossy = extras.get("glossy").map(|g| glb.glossy(g)).transpose()?;
        if let Some(frame) = glossy.as_ref().map(|g| &g.frame) {
            if frame.as_deref() != Some(crate::transfer::glossy::FRAME) {
                return Err(OtherFrame { file: name.to_string(), frame: frame.clone() }.into());
            }
        }
        let terms = glossy.as_ref().map_or(1, |g| g.terms);
        let channels = extras.get("channels").map_or(Some(1), Value::as_u64);
        let channels = match channels {
            Some(1) => 1,
            Some(3) if glossy.is_none() => 3,
            _ => return Err(bad("extras.prtkit.transfer.channels is not 1, or 3 for a diffuse bake").into()),
        };
        let albedo = match channels {
            1 => Some(extras["albedo"].as_f64().filter(|a| a.is_finite()).ok_or_else(|| bad("no finite albedo"))?),
            _ => None,
        };
        let primitive = &mesh["primitives"][0];
        let attributes = &primitive["attributes"];
        let (vertices, data) = glb.accessor(attributes, "POSITION", "VEC3", Storage::Float)?;
        let positions: Vec<[f32; 3]> = Storage::Float.read(data).chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        let coeffs = channels * terms * order * order;
        let quantized = glb.quantized(extras.get("quantization"))?;
        let (transfer, compressed) = match extras.get("cpca") {
            None => (glb.transfer(attributes, vertices, coeffs, &quantized)?, None),
            Some(c) => (Vec::new(), Some(glb.compressed(c, attributes, vertices, coeffs, &quantized)?)),
        };
        let indices = primitive["indices"].as_u64().ok_or_else(|| bad("no indices"))?;
        let count = glb.gltf["accessors"][indices as usize]["count"].as_u64();
        let triangles = count.ok_or_else(|| bad("the indices have no count"))? as usize / 3;
        Ok(TransferBake {
            name: name.to_string(),
            order,
            mode,
            albedo,
            channels,
            positions,
            triangles,
            transfer,
            glossy,
            compressed,
        })
    }

    /// Whether the bake is of `mesh`: the same vertices, at the same positions (to single
    /// precision, as the `.glb` stores them), and the same triangle count.
    pub fn check_mesh(&self, mesh: &Mesh) -> Result<(), OtherMesh> {
        if self.positions.len() != mesh.positions.len() || self.triangles != mesh.triangles.len() {
            return Err(OtherMesh::Size {
                bake: self.name.clone(),
                bake_vertices: self.positions.len(),
                bake_triangles: self.triangles,
                vertices: mesh.positions.len(),
                triangles: mesh.triangles.len(),
            });
        }
        if let Some(v) = self.positions.iter().zip(&mesh.positions).position(|(a, b)| *a != b.as_vec3().to_array()) {
            return Err(OtherMesh::Vertex { bake: self.name.clone(), vertex: v });
        }
        Ok(())
    }

    /// Coefficients per vertex and term, n².
    pub fn coefficients(&self) -> usize {
        self.order * self.order
    }

    /// Terms K (1 for diffuse bakes).
    pub fn terms(&self) -> usize {
        self.glossy.as_ref().map_or(1, |g| g.terms)
    }
}

/// The rotation about +Z by `degrees` (counter-clockwise seen from +Z): azimuth φ → φ + degrees.
pub fn rotation_about_z(degrees: f64) -> DMat3 {
    DMat3::from_rotation_z(degrees.to_radians())
}

/// One frame of relighting: the lighting `light` (RGB SH of highest band ≥ n − 1, in the mesh's
/// axes, as stored) turned by `rotation` (one SH rotation, Ivanic & Ruedenberg), then
/// B_v = Σ_i T_i(v) L_i per vertex in single precision, as a GPU would, into `out`.
/// For a glossy bake, the values are c_k per vertex and term (vertex-major): K dot products.
/// For a coloured bake, channel c's transfer is dotted with channel c of the lighting.
pub fn relight(bake: &TransferBake, light: &ShCoeffs, rotation: &ShRotation, out: &mut Vec<[f32; 3]>) {
    let turned = rotation.apply(&light.truncated(bake.order - 1));
    let l: Vec<[f32; 3]> = turned.rgb.iter().map(|c| c.map(|x| x as f32)).collect();
    let (coeffs, channels) = (bake.coefficients(), bake.channels);
    let dot = |t: &[f32]| dot_lighting(t, &l, channels);
    let stride = channels * coeffs;
    out.clear();
    let Some(c) = &bake.compressed else {
        out.extend(bake.transfer.chunks_exact(stride).map(dot));
        return;
    };
    // Clustered PCA (Sloan et al. 2003, eq. 3): the lighting against each cluster's mean and
    // directions once per frame, term by term; then P multiply-adds per vertex and term.
    let (terms, p) = (bake.terms(), c.components);
    let means: Vec<[f32; 3]> = c.means.chunks_exact(stride).map(dot).collect(); // C × K
    let bases: Vec<[f32; 3]> = c.bases.chunks_exact(stride).map(dot).collect(); // C × P × K
    for (&cluster, w) in c.cluster_of.iter().zip(c.weights.chunks_exact(p)) {
        let cluster = cluster as usize;
        for k in 0..terms {
            let mut b = means[cluster * terms + k];
            for (j, wj) in w.iter().enumerate() {
                let d = bases[(cluster * p + j) * terms + k];
                for ch in 0..3 {
                    b[ch] += wj * d[ch];
                }
            }
            out.push(b);
        }
    }
}

/// RGB radiance from one vertex's (or texel's) transfer `t` and the lighting's RGB coefficients
/// `l`, in single precision as a GPU would: B = Σ_i T_i L_i with one grey vector (`channels`
/// 1), or B_c = Σ_i T_ci L_ci with one vector per channel, channel-major (3). `l` holds the
/// bake's n² coefficients, so a channel's block of `t` is `l.len()` long. Always inlined, so
/// that the branch on `channels` leaves [`relight`]'s per-vertex loop: called out of line, the
/// grey dot product no longer vectorized and relighting slowed down (`docs/results/transfer.md`).
#[inline(always)]
fn dot_lighting(t: &[f32], l: &[[f32; 3]], channels: usize) -> [f32; 3] {
    let mut b = [0.0f32; 3];
    if channels == 1 {
        for (ti, li) in t.iter().zip(l) {
            b[0] += ti * li[0];
            b[1] += ti * li[1];
            b[2] += ti * li[2];
        }
    } else {
        for (c, block) in t.chunks_exact(l.len()).enumerate() {
            b[c] = block.iter().zip(l).map(|(ti, li)| ti * li[c]).sum();
        }
    }
    b
}

/// Shades a mesh hit by interpolating the per-vertex radiance of [`relight`] with the hit's
/// barycentrics (Gouraud shading, as the vertex-shader evaluation of PRT is drawn).
pub struct TransferShader<'a> {
    radiance: Vec<[f32; 3]>,
    triangles: &'a [[u32; 3]],
}

impl<'a> TransferShader<'a> {
    /// From one frame's per-vertex radiance and the mesh's triangles.
    pub fn new(radiance: Vec<[f32; 3]>, mesh: &'a Mesh) -> TransferShader<'a> {
        TransferShader { radiance, triangles: &mesh.triangles }
    }
}

impl Shade for TransferShader<'_> {
    fn shade(&self, hit: &Hit, _wo: DVec3) -> [f64; 3] {
        let Some((t, u, v)) = hit.triangle else {
            return [0.0; 3];
        };
        let [a, b, c] = self.triangles[t].map(|i| self.radiance[i as usize]);
        let w = 1.0 - u - v;
        std::array::from_fn(|k| w * a[k] as f64 + u * b[k] as f64 + v * c[k] as f64)
    }
}

/// A per-texel lightmap of diffuse transfer, read back from the EXR `transfer --lightmap` wrote
/// (`docs/formats/transfer.md`): its layers T0 … T{n²−1}.
#[derive(Clone, Debug)]
pub struct LightmapImage {
    /// The file, for messages.
    pub name: String,
    /// W.
    pub width: usize,
    /// H.
    pub height: usize,
    /// n² values per texel (3·n², channel-major, for a coloured bake), row-major, row y holding
    /// v = (y + ½)/H.
    pub transfer: Vec<f32>,
    /// n².
    pub coefficients: usize,
    /// 1, or 3 for a coloured bake (layers T_i with channels R, G, B).
    pub channels: usize,
}

impl LightmapImage {
    /// Reads the lightmap `path` for the diffuse, uncompressed `bake` it was written beside:
    /// n² layers of one size, every value finite.
    pub fn load(path: &std::path::Path, bake: &TransferBake) -> Result<LightmapImage, LightmapError> {
        let name = path.display().to_string();
        if bake.glossy.is_some() {
            return Err(LightmapError::Glossy { name, bake: bake.name.clone() });
        }
        let coefficients = bake.order * bake.order;
        let channels = bake.channels;
        let per_texel = channels * coefficients;
        let layers = crate::io::exr::read_layers(path)?;
        let layer = |i: usize| {
            let wanted = format!("T{i}");
            match layers.iter().find(|(n, _)| *n == wanted) {
                Some((_, image)) => Ok((wanted, image)),
                None => Err(LightmapError::MissingLayer { name: name.clone(), layer: wanted, order: bake.order }),
            }
        };
        let (_, first) = layer(0)?;
        let (width, height) = (first.width, first.height);
        if width == 0 || height == 0 {
            return Err(LightmapError::Empty { name });
        }
        let mut transfer = vec![0.0f32; width * height * per_texel];
        for i in 0..coefficients {
            let (wanted, image) = layer(i)?;
            if (image.width, image.height) != (width, height) {
                let size = (image.width, image.height);
                return Err(LightmapError::LayerSize { name, layer: wanted, size, first: (width, height) });
            }
            for (texel, px) in image.pixels.iter().enumerate() {
                if let Some(&value) = px.iter().find(|v| !v.is_finite()) {
                    let (x, y) = (texel % width, texel / width);
                    return Err(LightmapError::NotFinite { name, layer: wanted, x, y, value });
                }
                for (c, value) in px.iter().take(channels).enumerate() {
                    transfer[texel * per_texel + c * coefficients + i] = *value;
                }
            }
        }
        Ok(LightmapImage { name, width, height, transfer, coefficients, channels })
    }
}

/// Why a lightmap cannot relight a bake; each names the lightmap's file.
#[derive(Debug, thiserror::Error)]
pub enum LightmapError {
    /// The file cannot be read as an EXR.
    #[error(transparent)]
    Io(#[from] crate::io::IoError),
    /// A lightmap holds diffuse transfer; the bake is glossy.
    #[error("{name}: a lightmap relights a diffuse bake; {bake} is glossy")]
    Glossy {
        /// The lightmap.
        name: String,
        /// The bake.
        bake: String,
    },
    /// A layer T_i the bake's order needs is missing.
    #[error("{name}: no layer {layer}: not a lightmap of order {order}")]
    MissingLayer {
        /// The lightmap.
        name: String,
        /// The layer looked for.
        layer: String,
        /// The bake's SH order.
        order: usize,
    },
    /// The layers have no texels.
    #[error("{name}: the lightmap has no texels")]
    Empty {
        /// The lightmap.
        name: String,
    },
    /// A layer differs in size from T0 (the parts of a multi-part EXR may).
    #[error("{name}: layer {layer} is {}x{}, layer T0 is {}x{}: a lightmap's layers are one size", size.0, size.1, first.0, first.1)]
    LayerSize {
        /// The lightmap.
        name: String,
        /// The layer that differs.
        layer: String,
        /// Its width and height.
        size: (usize, usize),
        /// T0's.
        first: (usize, usize),
    },
    /// A transfer value is NaN or infinite.
    #[error("{name}: layer {layer} texel ({x}, {y}) is {value}: transfer values are finite")]
    NotFinite {
        /// The lightmap.
        name: String,
        /// The layer.
        layer: String,
        /// The texel's column.
        x: usize,
        /// Its row.
        y: usize,
        /// What it holds.
        value: f32,
    },
}

/// Shades a mesh hit from a lightmap: the lighting dotted with every texel's transfer once
/// (B = Σ_i T_i L_i, single precision, as [`relight`] does per vertex), then looked up
/// bilinearly at the hit's UV, interpolated from the triangle's vertices (texel centres at
/// ((x + ½)/W, (y + ½)/H), clamped at the grid's edges), as a lightmapped renderer samples it.
pub struct LightmapShader<'a> {
    radiance: Vec<[f32; 3]>,
    width: usize,
    height: usize,
    uvs: &'a [[f64; 2]],
    triangles: &'a [[u32; 3]],
}

impl<'a> LightmapShader<'a> {
    /// The lightmap relit by `light` turned by `rotation`, for the mesh whose UVs are `uvs`.
    pub fn new(
        lightmap: &LightmapImage,
        light: &ShCoeffs,
        rotation: &ShRotation,
        uvs: &'a [[f64; 2]],
        mesh: &'a Mesh,
    ) -> LightmapShader<'a> {
        let order = (lightmap.coefficients as f64).sqrt() as usize;
        let turned = rotation.apply(&light.truncated(order - 1));
        let l: Vec<[f32; 3]> = turned.rgb.iter().map(|c| c.map(|x| x as f32)).collect();
        let radiance = lightmap
            .transfer
            .chunks_exact(lightmap.channels * lightmap.coefficients)
            .map(|t| dot_lighting(t, &l, lightmap.channels))
            .collect();
        LightmapShader { radiance, width: lightmap.width, height: lightmap.height, uvs, triangles: &mesh.triangles }
    }
}

impl Shade for LightmapShader<'_> {
    fn shade(&self, hit: &Hit, _wo: DVec3) -> [f64; 3] {
        let Some((t, u, v)) = hit.triangle else {
            return [0.0; 3];
        };
        if self.width == 0 || self.height == 0 {
            return [0.0; 3];
        }
        let [a, b, c] = self.triangles[t].map(|i| self.uvs[i as usize]);
        let w = 1.0 - u - v;
        let uv = [w * a[0] + u * b[0] + v * c[0], w * a[1] + u * b[1] + v * c[1]];
        // Texel coordinates whose integers are texel centres.
        let x = (uv[0] * self.width as f64 - 0.5).clamp(0.0, (self.width - 1) as f64);
        let y = (uv[1] * self.height as f64 - 0.5).clamp(0.0, (self.height - 1) as f64);
        let (x0, y0) = (x.floor() as usize, y.floor() as usize);
        let (x1, y1) = ((x0 + 1).min(self.width - 1), (y0 + 1).min(self.height - 1));
        let (fx, fy) = (x - x0 as f64, y - y0 as f64);
        let at = |x: usize, y: usize| self.radiance[y * self.width + x].map(f64::from);
        let (p00, p10, p01, p11) = (at(x0, y0), at(x1, y0), at(x0, y1), at(x1, y1));
        std::array::from_fn(|k| {
            (1.0 - fy) * ((1.0 - fx) * p00[k] + fx * p10[k]) + fy * ((1.0 - fx) * p01[k] + fx * p11[k])
        })
    }
}
