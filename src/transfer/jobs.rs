//! A bake split into independent jobs, so that `make -j` or a build farm spreads it (issue 32,
//! "Scale"). Job I of N integrates the per-vertex transfer of the I-th of N contiguous vertex
//! ranges against the whole scene (the BVH holds every triangle) and writes it as a [`Part`]
//! (`docs/formats/transfer-part.md`); the join reads the N parts and does what follows the
//! per-vertex integration (the error figures, clustered PCA, quantization, the lightmap, the
//! `.glb` and the snippets) exactly as one run does. A vertex's transfer depends only on the
//! scene, the options and the vertex — its sums run in a fixed order, the directions' or the
//! factor cells' — not on which vertices share its job, so the joined outputs are byte-identical
//! to one run's.
//!
//! Interreflections are not split: each bounce gathers the transfer of every vertex.

use super::diffuse::PointTransfer;
use super::stage::{Config, Mode};
use crate::mesh::Mesh;
use serde::{Deserialize, Serialize};
use std::ops::Range;

/// The part file's first bytes.
pub const MAGIC: &[u8; 8] = b"PRTKPART";
/// The header's `format`.
pub const FORMAT: &str = "prtkit.transfer-part";
/// The header's `version`.
pub const VERSION: u32 = 1;

/// Job `index` (1-based) of `count`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Job {
    /// I, from 1.
    pub index: usize,
    /// N.
    pub count: usize,
}

impl Job {
    /// Parses `I/N`, 1 ≤ I ≤ N ≤ [`crate::limits::MAX_TRANSFER_JOBS`].
    pub fn parse(s: &str) -> Result<Job, String> {
        let parsed = s.split_once('/').and_then(|(i, n)| Some((i.trim().parse().ok()?, n.trim().parse().ok()?)));
        match parsed {
            Some((index, count)) if (1..=count).contains(&index) && count <= crate::limits::MAX_TRANSFER_JOBS => {
                Ok(Job { index, count })
            }
            _ => Err(format!("{s:?}: a job is I/N with 1 <= I <= N <= {}, e.g. 3/8", crate::limits::MAX_TRANSFER_JOBS)),
        }
    }

    /// The job's share of `total` vertices, [⌊(I−1)·V/N⌋, ⌊I·V/N⌋): the N ranges tile 0..V.
    pub fn vertices(&self, total: usize) -> Range<usize> {
        let at = |k: usize| (total as u128 * k as u128 / self.count as u128) as usize;
        at(self.index - 1)..at(self.index)
    }
}

/// What a part was baked from: every option that changes a vertex's transfer, and digests of the
/// scene and of the factors kept. A join compares it with its own, field by field.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Recipe {
    /// SH order n.
    pub order: usize,
    /// Unshadowed, shadowed or interreflected.
    pub mode: Mode,
    /// Ray directions per vertex.
    pub rays: usize,
    /// Seed of the directions' jitter.
    pub seed: u64,
    /// The albedo folded into the part's values: the grey albedo, or 1 for a coloured bake,
    /// whose channels the join makes ([`super::albedo`]).
    pub albedo: f64,
    /// The ray origin offset, relative to the bounding-box diagonal.
    pub offset: f64,
    /// Glossy bakes: the terms kept, the basis samples per cell, and the digest of the factors'
    /// grid, σ_k and g_k for those terms.
    pub glossy: Option<GlossyRecipe>,
    /// The scene's vertex count.
    pub vertices: usize,
    /// FNV-1a (64-bit) of the scene's positions, normals and triangles as the bake reads them.
    pub mesh_digest: String,
}

/// The glossy half of a [`Recipe`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GlossyRecipe {
    /// Terms K kept.
    pub terms: usize,
    /// Basis samples per cell along each axis.
    pub cell_samples: usize,
    /// Whether max(cos θ_i, 0) is folded into the factors.
    pub cosine: bool,
    /// FNV-1a (64-bit) of the grid's size and domain and of σ_k, g_k for the terms kept.
    pub factors_digest: String,
}

impl Recipe {
    /// The recipe of `config` on `mesh`.
    pub fn new(config: &Config, mesh: &Mesh) -> Recipe {
        let mut scene = Fnv::default();
        for p in mesh.positions.iter().chain(&mesh.normals) {
            p.to_array().iter().for_each(|c| scene.write(&c.to_le_bytes()));
        }
        mesh.triangles.iter().flatten().for_each(|i| scene.write(&i.to_le_bytes()));
        let glossy = config.glossy.as_ref().map(|g| {
            let f = &g.factorization;
            let mut factors = Fnv::default();
            factors.write(&(f.grid.n as u64).to_le_bytes());
            factors.write(format!("{:?}", f.grid.domain).as_bytes());
            for (sigma, g) in f.singular_values.iter().zip(&f.g).take(g.terms) {
                std::iter::once(sigma).chain(g).for_each(|v| factors.write(&v.to_le_bytes()));
            }
            GlossyRecipe {
                terms: g.terms,
                cell_samples: g.cell_samples,
                cosine: g.cosine,
                factors_digest: factors.hex(),
            }
        });
        Recipe {
            order: config.order,
            mode: config.mode,
            rays: config.rays,
            seed: config.seed,
            albedo: config.albedo.folded(),
            offset: config.offset,
            glossy,
            vertices: mesh.positions.len(),
            mesh_digest: scene.hex(),
        }
    }

    /// Whether its parts carry the estimates of the error figures: diffuse shadowed bakes.
    fn has_estimates(&self) -> bool {
        self.mode == Mode::Shadowed && self.glossy.is_none()
    }

    /// The first field in which `self` (a part's) differs from `want` (the join's), in words.
    fn difference(&self, want: &Recipe) -> Option<String> {
        let (ours, theirs) = (serde_json::to_value(self).ok()?, serde_json::to_value(want).ok()?);
        let (ours, theirs) = (ours.as_object()?, theirs.as_object()?);
        theirs.iter().find(|(k, v)| ours.get(*k) != Some(v)).map(|(k, v)| {
            let part = ours.get(k).map_or("nothing".into(), |p| p.to_string());
            format!("baked with {k} = {part}, where this join has {v}")
        })
    }
}

/// FNV-1a, 64-bit (Fowler, Noll & Vo): a digest to tell scenes apart, not a cryptographic hash.
struct Fnv(u64);

impl Default for Fnv {
    fn default() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv {
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ b as u64).wrapping_mul(0x0100_0000_01b3);
        }
    }

    fn hex(&self) -> String {
        format!("{:016x}", self.0)
    }
}

/// The part file's JSON header.
#[derive(Debug, Serialize, Deserialize)]
struct Header {
    format: String,
    version: u32,
    recipe: Recipe,
    /// The vertex range [start, end).
    vertices: [usize; 2],
    /// Values per vertex.
    per_vertex: usize,
    /// Whether the diffuse shadowed estimates follow the transfer.
    estimates: bool,
}

/// One job's output: the transfer of its vertices and, for a diffuse shadowed bake, what the
/// manifest's error figures are computed from.
#[derive(Clone, Debug, PartialEq)]
pub struct Part {
    /// What it was baked from.
    pub recipe: Recipe,
    /// Its vertices [start, end).
    pub vertices: Range<usize>,
    /// Values per vertex.
    pub per_vertex: usize,
    /// `per_vertex` values per vertex of the range.
    pub transfer: Vec<f64>,
    /// Diffuse shadowed bakes: per vertex, the same rays with V ≡ 1 (n² values) and the rays
    /// that escaped ([`PointTransfer`]).
    pub estimates: Option<(Vec<f64>, Vec<u32>)>,
}

impl Part {
    /// The part of `vertices` from their transfer, or from their [`PointTransfer`]s.
    pub fn new(recipe: Recipe, vertices: Range<usize>, per_vertex: usize, transfer: Transfer) -> Part {
        let (transfer, estimates) = match transfer {
            Transfer::Values(values) => (values, None),
            Transfer::Points(points) => {
                let transfer = points.iter().flat_map(|p| p.shadowed.iter().copied()).collect();
                let unshadowed = points.iter().flat_map(|p| p.unshadowed.iter().copied()).collect();
                (transfer, Some((unshadowed, points.iter().map(|p| p.visible).collect())))
            }
        };
        Part { recipe, vertices, per_vertex, transfer, estimates }
    }

    /// The file: [`MAGIC`], the header's length (u32 LE), the header (JSON), then the transfer
    /// (f64 LE) and, with estimates, the V ≡ 1 values (f64 LE) and the escaped rays (u32 LE).
    pub fn encode(&self) -> Vec<u8> {
        let header = Header {
            format: FORMAT.into(),
            version: VERSION,
            recipe: self.recipe.clone(),
            vertices: [self.vertices.start, self.vertices.end],
            per_vertex: self.per_vertex,
            estimates: self.estimates.is_some(),
        };
        let json = serde_json::to_vec(&header).expect("a header serializes");
        let mut out = Vec::with_capacity(12 + json.len() + 8 * self.transfer.len());
        out.extend(MAGIC);
        out.extend((json.len() as u32).to_le_bytes());
        out.extend(json);
        self.transfer.iter().for_each(|v| out.extend(v.to_le_bytes()));
        if let Some((unshadowed, visible)) = &self.estimates {
            unshadowed.iter().for_each(|v| out.extend(v.to_le_bytes()));
            visible.iter().for_each(|v| out.extend(v.to_le_bytes()));
        }
        out
    }

    /// Reads a part file's bytes; the error says what is wrong (the caller names the file).
    pub fn decode(bytes: &[u8]) -> Result<Part, String> {
        let rest = bytes.strip_prefix(MAGIC).ok_or("not a transfer part (no PRTKPART magic)")?;
        let (len, rest) = rest.split_first_chunk::<4>().ok_or("the file ends inside its header")?;
        let len = u32::from_le_bytes(*len) as usize;
        let json = rest.get(..len).ok_or("the file ends inside its header")?;
        let header: Header = serde_json::from_slice(json).map_err(|e| format!("its header: {e}"))?;
        if header.format != FORMAT || header.version != VERSION {
            return Err(format!("a {} version {} file, not {FORMAT} version {VERSION}", header.format, header.version));
        }
        let [start, end] = header.vertices;
        if start > end || end > header.recipe.vertices || header.per_vertex == 0 {
            return Err(format!("its vertex range {start}..{end} or {} values per vertex", header.per_vertex));
        }
        let n = end - start;
        let coeffs = header.recipe.order * header.recipe.order;
        let want =
            n as u128 * (8 * header.per_vertex as u128 + if header.estimates { 8 * coeffs as u128 + 4 } else { 0 });
        let body = &rest[len..];
        if body.len() as u128 != want {
            return Err(format!("{} bytes of values where its header says {want}", body.len()));
        }
        let (values, tail) = body.split_at(8 * n * header.per_vertex);
        let transfer = f64s(values)?;
        let estimates = if header.estimates {
            let (unshadowed, visible) = tail.split_at(8 * n * coeffs);
            let visible = visible.chunks_exact(4).map(|b| u32::from_le_bytes(b.try_into().expect("four bytes")));
            Some((f64s(unshadowed)?, visible.collect()))
        } else {
            None
        };
        Ok(Part { recipe: header.recipe, vertices: start..end, per_vertex: header.per_vertex, transfer, estimates })
    }
}

/// Reads the part file at `path` whole, within [`crate::limits::max_file_bytes`].
pub fn read_part(path: &std::path::Path) -> Result<(String, Part), super::stage::Error> {
    let file = path.display().to_string();
    let bytes = crate::io::read_bytes(path, "transfer part", crate::limits::max_file_bytes(), |start| {
        match start.starts_with(&MAGIC[..start.len().min(MAGIC.len())]) {
            true => Ok(()),
            false => Err("no PRTKPART magic".into()),
        }
    })?;
    let part = Part::decode(&bytes).map_err(|reason| super::stage::Error::Part { file: file.clone(), reason })?;
    Ok((file, part))
}

/// Finite f64s from little-endian bytes.
fn f64s(bytes: &[u8]) -> Result<Vec<f64>, String> {
    let values: Vec<f64> =
        bytes.chunks_exact(8).map(|b| f64::from_le_bytes(b.try_into().expect("eight bytes"))).collect();
    match values.iter().any(|v| !v.is_finite()) {
        true => Err("a value is not finite".into()),
        false => Ok(values),
    }
}

/// What a job integrates: plain values, or a diffuse shadowed bake's [`PointTransfer`]s.
pub enum Transfer {
    /// The values, vertex after vertex.
    Values(Vec<f64>),
    /// Per vertex, the shadowed transfer and its estimates.
    Points(Vec<PointTransfer>),
}

/// The parts of one bake, checked as they are added: each of the join's recipe and values per
/// vertex, none overlapping another.
pub struct Joined {
    recipe: Recipe,
    per_vertex: usize,
    parts: Vec<Part>,
}

impl Joined {
    /// An empty join for `recipe` and `per_vertex` values per vertex.
    pub fn new(recipe: Recipe, per_vertex: usize) -> Joined {
        Joined { recipe, per_vertex, parts: Vec::new() }
    }

    /// Adds a part; the error says why it does not belong (the caller names the file).
    pub fn add(&mut self, part: Part) -> Result<(), String> {
        if let Some(difference) = part.recipe.difference(&self.recipe) {
            return Err(format!("not a part of this bake: {difference}"));
        }
        if part.per_vertex != self.per_vertex || part.estimates.is_some() != self.recipe.has_estimates() {
            return Err(format!("{} values per vertex, where this bake has {}", part.per_vertex, self.per_vertex));
        }
        let r = &part.vertices;
        if let Some(other) = self.parts.iter().find(|p| p.vertices.start < r.end && r.start < p.vertices.end) {
            return Err(format!("its vertices {r:?} overlap another part's, {:?}", other.vertices));
        }
        self.parts.push(part);
        Ok(())
    }

    /// The transfer of every vertex in order, once the parts cover them all: else the first
    /// vertex range none holds.
    pub fn finish(mut self) -> Result<Transfer, Range<usize>> {
        self.parts.sort_by_key(|p| p.vertices.start);
        let mut next = 0;
        for p in &self.parts {
            if p.vertices.start > next {
                return Err(next..p.vertices.start);
            }
            next = p.vertices.end;
        }
        if next < self.recipe.vertices {
            return Err(next..self.recipe.vertices);
        }
        let coeffs = self.recipe.order * self.recipe.order;
        if !self.recipe.has_estimates() {
            return Ok(Transfer::Values(self.parts.into_iter().flat_map(|p| p.transfer).collect()));
        }
        let points = self.parts.into_iter().flat_map(|p| {
            let (unshadowed, visible) = p.estimates.expect("a shadowed part has estimates");
            let shadowed: Vec<Vec<f64>> = p.transfer.chunks_exact(coeffs).map(<[f64]>::to_vec).collect();
            let unshadowed: Vec<Vec<f64>> = unshadowed.chunks_exact(coeffs).map(<[f64]>::to_vec).collect();
            shadowed
                .into_iter()
                .zip(unshadowed)
                .zip(visible)
                .map(|((shadowed, unshadowed), visible)| PointTransfer { shadowed, unshadowed, visible })
                .collect::<Vec<_>>()
        });
        Ok(Transfer::Points(points.collect()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jobs_tile_the_vertices_and_parse_as_i_of_n() {
        for (total, count) in [(0, 1), (1, 3), (10, 3), (1507, 8), (100_000, 7)] {
            let mut next = 0;
            for index in 1..=count {
                let r = Job { index, count }.vertices(total);
                assert_eq!(r.start, next, "{total} {count}");
                next = r.end;
            }
            assert_eq!(next, total);
        }
        assert_eq!(Job::parse("3/8"), Ok(Job { index: 3, count: 8 }));
        for bad in ["0/8", "9/8", "8", "a/b", "1/0", "1/1000000000"] {
            assert!(Job::parse(bad).is_err(), "{bad}");
        }
    }

    fn recipe(mode: Mode) -> Recipe {
        Recipe {
            order: 2,
            mode,
            rays: 16,
            seed: 0,
            albedo: 1.0,
            offset: 1e-4,
            glossy: None,
            vertices: 5,
            mesh_digest: "0123456789abcdef".into(),
        }
    }

    #[test]
    fn a_part_reads_back_as_written_and_truncation_is_refused() {
        let points: Vec<PointTransfer> = (0..3)
            .map(|v| PointTransfer {
                shadowed: (0..4).map(|i| (v * 4 + i) as f64 * 0.1).collect(),
                unshadowed: (0..4).map(|i| -(i as f64)).collect(),
                visible: v as u32,
            })
            .collect();
        let part = Part::new(recipe(Mode::Shadowed), 1..4, 4, Transfer::Points(points));
        let bytes = part.encode();
        assert_eq!(Part::decode(&bytes).unwrap(), part);
        assert!(Part::decode(&bytes[..bytes.len() - 1]).unwrap_err().contains("bytes of values"));
        assert!(Part::decode(b"PRTKPARX").unwrap_err().contains("magic"));
    }

    #[test]
    fn a_join_refuses_other_recipes_overlaps_and_gaps() {
        let values = |r: Range<usize>| {
            Part::new(recipe(Mode::Unshadowed), r.clone(), 4, Transfer::Values(vec![1.0; 4 * r.len()]))
        };
        let mut join = Joined::new(recipe(Mode::Unshadowed), 4);
        join.add(values(0..2)).unwrap();
        assert!(join.add(values(1..3)).unwrap_err().contains("overlap"));
        let mut other = values(2..3);
        other.recipe.rays = 32;
        assert!(join.add(other).unwrap_err().contains("rays = 32, where this join has 16"));
        join.add(values(3..5)).unwrap();
        assert_eq!(join.finish().err(), Some(2..3));
    }
}
