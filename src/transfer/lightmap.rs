//! Per-texel diffuse transfer in a lightmap: the transfer vector T_i of
//! [`super::diffuse`] computed at the centre of every texel of a W×H grid in the mesh's UV
//! space, instead of at its vertices. Sloan, Kautz & Snyder 2002 bake their lightmapped
//! examples this way: a vertex bake interpolates T linearly across a triangle, so a shadow
//! that falls inside a large triangle (a ball's on a two-triangle floor) is lost, while the
//! lightmap samples it at its own resolution.
//!
//! **Coverage.** A texel (x, y) is covered when its centre ((x + ½)/W, (y + ½)/H) lies inside a
//! triangle in UV, by edge functions. Each edge's function is computed from its endpoints in a
//! canonical (lexicographic) order and negated for the triangle that runs it the other way, so
//! the two triangles sharing an edge get exactly opposite values, bit for bit; a centre exactly
//! on the edge goes to one of them by a tie rule on the edge's direction (as the top-left rule
//! of rasterizers: Pineda 1988's edge functions): no texel is covered twice or dropped along a
//! shared edge. Where UV charts overlap, the triangle of lowest index keeps the texel (and the
//! overlaps are counted). UVs outside [0, 1] are not wrapped: texels only exist inside.
//!
//! **Dilation.** Bilinear lookups at a chart's border read texels half outside it; those are
//! filled by [`DILATION`] rounds in which each empty texel takes the value of a filled
//! neighbour (4-neighbours first, then diagonals, in a fixed order), so the border texels repeat
//! the chart's edge rather than blend with black.
//!
//! **The integrand is the vertex bake's.** At a covered texel the world position and the normal
//! (renormalized) are interpolated from the triangle's vertices by the barycentrics of the texel
//! centre in UV, then T is [`unshadowed_exact`] or [`Shadowed::integrate`] with the same
//! directions, BVH and offset as the per-vertex bake: a texel at a vertex's UV gets that
//! vertex's T to rounding.

use super::atlas::{Atlas, AtlasInfo};
use super::diffuse::{unshadowed_exact, Shadowed};
use super::directions::Stratified;
use super::interreflect::Tracer;
use super::stage::{Config, Error, Mode};
use super::visibility::Occluders;
use crate::limits::{LimitError, MAX_IMAGE_TEXELS, MAX_LIGHTMAP_SIDE, MAX_LIGHTMAP_VALUES};
use crate::mesh::Mesh;
use crate::progress::Progress;
use glam::DVec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Dilation rounds: each fills the empty texels next to a filled one. Two cover the one texel
/// a bilinear lookup reads beyond the chart's last covered centre, and one more of margin for a
/// mip level's box filter.
pub const DILATION: usize = 2;
/// Texels per parallel work item and per unit of progress.
const CHUNK: usize = 256;
/// The value of a dilated texel in the `coverage` layer (covered 1, empty 0).
pub const DILATED: f32 = 0.5;

/// Where a lightmap's UVs come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightmapUvs {
    /// The mesh's own UV set (`--lightmap`).
    Mesh,
    /// A generated atlas ([`Atlas`]); the mesh's own UVs are ignored (`--texels`).
    Atlas,
}

/// What `transfer --lightmap WxH FILE.exr` (or `--texels`) asks for.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LightmapConfig {
    /// Texels across (W).
    pub width: usize,
    /// Texels down (H).
    pub height: usize,
    /// The EXR's file name, for the manifest.
    pub file: String,
    /// The UV set baked.
    pub uvs: LightmapUvs,
}

/// The manifest's account of the lightmap (`docs/formats/transfer.md`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct LightmapInfo {
    /// The EXR's file name.
    pub file: String,
    /// W.
    pub width: usize,
    /// H.
    pub height: usize,
    /// The EXR's layers in coefficient order, then `coverage`.
    pub layers: Vec<String>,
    /// Texels whose centre lies in a triangle.
    pub texels_covered: usize,
    /// Empty texels filled by dilation.
    pub texels_dilated: usize,
    /// Dilation rounds.
    pub dilation: usize,
    /// Texels that more than one triangle covers (overlapping UV charts; the lowest triangle
    /// index keeps them).
    pub texels_overlapping: usize,
    /// The UV set read.
    pub uvs: String,
    /// The layout in words.
    pub layout: String,
    /// The generated atlas (`--texels`; absent for the mesh's own UVs).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub atlas: Option<AtlasInfo>,
}

/// One covered texel: its triangle and the barycentric weights of the triangle's vertices at
/// its centre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// The mesh's triangle.
    pub triangle: u32,
    /// Weights of its vertices 0, 1, 2 (summing to one).
    pub weights: [f64; 3],
}

/// Which triangle covers each texel of the grid.
#[derive(Clone, Debug)]
pub struct Coverage {
    /// W.
    pub width: usize,
    /// H.
    pub height: usize,
    /// Row-major, row y holding v = (y + ½)/H.
    pub samples: Vec<Option<Sample>>,
    /// Texels covered by more than one triangle.
    pub overlapping: usize,
}

/// The edge function of the directed edge a → b at p: twice the signed area of (a, b, p),
/// positive when p is to the left. Computed with the endpoints in lexicographic order and
/// negated when a → b runs the other way, so that the triangle on either side of an edge gets
/// the same magnitude, bit for bit.
fn edge(a: [f64; 2], b: [f64; 2], p: [f64; 2]) -> f64 {
    let (lo, hi, sign) = if (a[0], a[1]) <= (b[0], b[1]) { (a, b, 1.0) } else { (b, a, -1.0) };
    sign * ((hi[0] - lo[0]) * (p[1] - lo[1]) - (hi[1] - lo[1]) * (p[0] - lo[0]))
}

/// Whether a centre exactly on the directed edge a → b belongs to the triangle on its left: of
/// the two directions of one edge, exactly one passes.
fn owns_ties(a: [f64; 2], b: [f64; 2]) -> bool {
    let d = [b[0] - a[0], b[1] - a[1]];
    d[1] > 0.0 || (d[1] == 0.0 && d[0] < 0.0)
}

/// Rasterizes every triangle's UVs (`uvs`, one per vertex) into a `width`×`height` grid.
pub fn rasterize(uvs: &[[f64; 2]], triangles: &[[u32; 3]], width: usize, height: usize) -> Coverage {
    let mut samples: Vec<Option<Sample>> = vec![None; width * height];
    let mut overlapping = 0;
    let (w, h) = (width as f64, height as f64);
    for (index, t) in triangles.iter().enumerate() {
        // In texel units, where centres sit at x + ½.
        let mut corner = t.map(|i| {
            let [u, v] = uvs[i as usize];
            [u * w, v * h]
        });
        let mut order = [0, 1, 2];
        let area = edge(corner[0], corner[1], corner[2]);
        if area == 0.0 || !area.is_finite() {
            continue;
        }
        // Counter-clockwise in (u, v): swap two corners of a clockwise triangle.
        if area < 0.0 {
            corner.swap(1, 2);
            order.swap(1, 2);
        }
        let area = edge(corner[0], corner[1], corner[2]);
        let lo = |k: usize| corner.iter().map(|c| c[k]).fold(f64::INFINITY, f64::min);
        let hi = |k: usize| corner.iter().map(|c| c[k]).fold(f64::NEG_INFINITY, f64::max);
        // The centres x + ½ within [lo, hi], clamped to the grid; none when the range is empty.
        let range = |lo: f64, hi: f64, n: usize| {
            let first = (lo - 0.5).ceil().max(0.0);
            let last = (hi - 0.5).floor().min(n as f64 - 1.0);
            (first <= last).then_some((first as usize, last as usize))
        };
        let (Some((x0, x1)), Some((y0, y1))) = (range(lo(0), hi(0), width), range(lo(1), hi(1), height)) else {
            continue;
        };
        let edges = [(1, 2), (2, 0), (0, 1)];
        let ties = edges.map(|(i, j)| owns_ties(corner[i], corner[j]));
        for y in y0..=y1 {
            for x in x0..=x1 {
                let p = [x as f64 + 0.5, y as f64 + 0.5];
                let e = edges.map(|(i, j)| edge(corner[i], corner[j], p));
                if !(0..3).all(|k| e[k] > 0.0 || (e[k] == 0.0 && ties[k])) {
                    continue;
                }
                // e[k] is the weight of the corner opposite edge k, times the area.
                let mut weights = [0.0; 3];
                for k in 0..3 {
                    weights[order[k]] = e[k] / area;
                }
                let slot = &mut samples[y * width + x];
                match slot {
                    Some(_) => overlapping += 1,
                    None => *slot = Some(Sample { triangle: index as u32, weights }),
                }
            }
        }
    }
    Coverage { width, height, samples, overlapping }
}

/// For every texel, the covered texel whose value it holds: itself when covered, a neighbour's
/// source after dilation, `None` when empty.
pub fn dilate(coverage: &Coverage, rounds: usize) -> Vec<Option<usize>> {
    let (w, h) = (coverage.width as i64, coverage.height as i64);
    let mut source: Vec<Option<usize>> = coverage.samples.iter().enumerate().map(|(i, s)| s.map(|_| i)).collect();
    const NEIGHBOURS: [(i64, i64); 8] = [(-1, 0), (1, 0), (0, -1), (0, 1), (-1, -1), (1, -1), (-1, 1), (1, 1)];
    for _ in 0..rounds {
        let previous = source.clone();
        for y in 0..h {
            for x in 0..w {
                let i = (y * w + x) as usize;
                if previous[i].is_some() {
                    continue;
                }
                source[i] = NEIGHBOURS.iter().find_map(|&(dx, dy)| {
                    let (nx, ny) = (x + dx, y + dy);
                    ((0..w).contains(&nx) && (0..h).contains(&ny)).then(|| previous[(ny * w + nx) as usize]).flatten()
                });
            }
        }
    }
    source
}

/// Checks a lightmap request before anything is baked: the mesh has UVs (unless an atlas makes
/// them), the grid is within [`MAX_LIGHTMAP_SIDE`] and [`MAX_LIGHTMAP_VALUES`], and the mode is
/// one the lightmap bakes.
pub fn check(lightmap: &LightmapConfig, config: &Config, mesh: &Mesh) -> Result<(), Error> {
    let name = &config.source;
    if mesh.uvs.is_none() && lightmap.uvs == LightmapUvs::Mesh {
        return Err(Error::NoUvs(name.clone()));
    }
    let (w, h) = (lightmap.width, lightmap.height);
    if w == 0 || h == 0 {
        return Err(Error::NoTexels { source_name: name.clone(), width: w, height: h });
    }
    let limit = |error: LimitError| Error::Limit { source_name: name.clone(), error };
    for (side, what) in [(w, "width"), (h, "height")] {
        crate::limits::check_count(
            &format!("the lightmap's {what}"),
            side,
            MAX_LIGHTMAP_SIDE,
            "W x H stays within the largest image prtkit reads",
        )
        .map_err(limit)?;
    }
    let values = w as u64 * h as u64 * (config.order * config.order) as u64;
    if values > MAX_LIGHTMAP_VALUES {
        return Err(limit(LimitError {
            what: format!("the value count of a {w}x{h} lightmap of order {}", config.order),
            value: values.to_string(),
            ceiling: MAX_LIGHTMAP_VALUES.to_string(),
            reason: "W x H x n^2 as f32 in one EXR",
        }));
    }
    debug_assert!((w * h) as u64 <= MAX_IMAGE_TEXELS);
    // f64 values while baking, f32 layers to write, the coverage samples.
    crate::limits::check_memory("the lightmap", values as u128 * 12 + (w * h) as u128 * 48).map_err(limit)?;
    let unbuilt = if config.glossy.is_some() {
        Some("glossy")
    } else if config.compression.is_some() {
        Some("compressed")
    } else {
        None
    };
    if let Some(bake) = unbuilt {
        return Err(Error::LightmapOf { source_name: name.clone(), bake });
    }
    Ok(())
}

/// The mesh a lightmap bakes: `mesh` itself for its own UVs; for a generated atlas (after
/// [`check`]), `mesh` split along the atlas's seams with the atlas's UVs, and the atlas's account.
pub fn atlas_mesh(lightmap: &LightmapConfig, config: &Config, mesh: &Mesh) -> Result<Option<(Mesh, AtlasInfo)>, Error> {
    if lightmap.uvs == LightmapUvs::Mesh {
        return Ok(None);
    }
    check(lightmap, config, mesh)?;
    let atlas = Atlas::new(&mesh.positions, &mesh.triangles, lightmap.width, lightmap.height)
        .map_err(|error| Error::Atlas { source_name: config.source.clone(), error })?;
    let copy = |v: &[DVec3]| atlas.vertex_of.iter().map(|&i| v[i as usize]).collect();
    // The split triangles index the copies, so they are in range.
    let mut split = Mesh::new(copy(&mesh.positions), Some(copy(&mesh.normals)), atlas.triangles)
        .expect("the atlas's triangles index its vertices");
    split.normals_computed = mesh.normals_computed;
    split.uvs = Some(atlas.uvs);
    split.base_colors = mesh.base_colors.as_ref().map(|c| atlas.vertex_of.iter().map(|&i| c[i as usize]).collect());
    Ok(Some((split, atlas.info)))
}

/// A baked lightmap: the EXR's bytes and the manifest's account.
#[derive(Clone, Debug)]
pub struct Lightmap {
    /// The EXR.
    pub exr: Vec<u8>,
    /// What the manifest says of it.
    pub info: LightmapInfo,
    /// The transfer, n² values per texel (3·n², channel-major, with a coloured albedo),
    /// row-major (zeros at empty texels).
    pub transfer: Vec<f64>,
    /// 1 covered, [`DILATED`] dilated, 0 empty.
    pub coverage: Vec<f32>,
}

/// Bakes the lightmap of `mesh` (checked by [`check`]) with `config`'s integrator. Given
/// `gathered` (an interreflected bake: every vertex's T^0 + … + T^{B−1}), each texel gathers it
/// at its rays' front hits ([`Tracer::gather_at`]).
pub fn bake(
    lightmap: &LightmapConfig,
    config: &Config,
    mesh: &Mesh,
    gathered: Option<&[f64]>,
    progress: &dyn Progress,
) -> Result<Lightmap, Error> {
    check(lightmap, config, mesh)?;
    let uvs = mesh.uvs.as_deref().unwrap_or_default();
    let (width, height) = (lightmap.width, lightmap.height);
    let n = config.order;
    let coeffs = n * n;
    // A coloured albedo: each texel's ρ_c interpolated from its triangle's vertices, as the
    // vertex bake's T is, and one transfer vector per channel ([`super::albedo`]).
    let colours = config.albedo.colours(mesh);
    let channels = config.albedo.channels();
    let per_texel = channels * coeffs;
    let coverage = rasterize(uvs, &mesh.triangles, width, height);
    let covered: Vec<(usize, Sample)> =
        coverage.samples.iter().enumerate().filter_map(|(i, s)| s.map(|s| (i, s))).collect();
    let point = |s: &Sample| {
        let t = mesh.triangles[s.triangle as usize].map(|i| i as usize);
        let mix = |v: &[DVec3]| s.weights[0] * v[t[0]] + s.weights[1] * v[t[1]] + s.weights[2] * v[t[2]];
        (mix(&mesh.positions), mix(&mesh.normals).try_normalize().unwrap_or(mesh.normals[t[0]]))
    };
    let albedo = |s: &Sample| -> Vec<f64> {
        match &colours {
            None => vec![config.albedo.folded()],
            Some(c) => {
                let t = mesh.triangles[s.triangle as usize].map(|i| c[i as usize]);
                (0..3).map(|k| s.weights[0] * t[0][k] + s.weights[1] * t[1][k] + s.weights[2] * t[2][k]).collect()
            }
        }
    };
    // The grey transfer (ρ folded in, 1 when coloured) spread over the channels.
    let spread = |grey: &[f64], rho: &[f64], out: &mut [f64]| match rho {
        [_] => out.copy_from_slice(grey),
        _ => {
            for (block, r) in out.chunks_exact_mut(coeffs).zip(rho) {
                block.iter_mut().zip(grey).for_each(|(o, g)| *o = r * g);
            }
        }
    };
    let folded = config.albedo.folded();
    let mut values = vec![0.0; covered.len() * per_texel];
    let offset = config.offset * mesh.extent();
    // Each texel's sums run in a fixed order; chunks are independent: the same bits for any
    // thread count.
    match config.mode {
        Mode::Unshadowed => {
            progress.start("lightmap (unshadowed)", covered.len() as u64);
            values.par_chunks_mut(CHUNK * per_texel).zip(covered.par_chunks(CHUNK)).for_each(|(out, texels)| {
                let mut grey = vec![0.0; coeffs];
                for (t, (_, s)) in out.chunks_exact_mut(per_texel).zip(texels) {
                    unshadowed_exact(point(s).1, n, folded, &mut grey);
                    spread(&grey, &albedo(s), t);
                }
                progress.advance(texels.len() as u64);
            });
        }
        _ => {
            let occluders = Occluders::new(&mesh.positions, &mesh.triangles);
            let directions = Stratified::new(config.rays, config.seed);
            let shadowed = Shadowed::new(&directions, n, &occluders);
            let tracer = Tracer::new(mesh, &occluders, &directions, n, offset);
            progress.start("lightmap (visibility)", covered.len() as u64);
            values.par_chunks_mut(CHUNK * per_texel).zip(covered.par_chunks(CHUNK)).for_each(|(out, texels)| {
                for (t, (_, s)) in out.chunks_exact_mut(per_texel).zip(texels) {
                    let (p, normal) = point(s);
                    let rho = albedo(s);
                    match gathered {
                        Some(g) => t.copy_from_slice(&tracer.gather_at(p, normal, &rho, g)),
                        None => spread(&shadowed.integrate(p, normal, offset, folded).shadowed, &rho, t),
                    }
                }
                progress.advance(texels.len() as u64);
            });
        }
    }
    progress.finish();
    let mut slot_of = vec![usize::MAX; width * height];
    for (k, (i, _)) in covered.iter().enumerate() {
        slot_of[*i] = k;
    }
    let sources = dilate(&coverage, DILATION);
    let mut transfer = vec![0.0; width * height * per_texel];
    let mut coverage_layer = vec![0.0f32; width * height];
    let mut dilated = 0;
    for (i, source) in sources.iter().enumerate() {
        let Some(j) = *source else { continue };
        let k = slot_of[j];
        transfer[i * per_texel..(i + 1) * per_texel].copy_from_slice(&values[k * per_texel..(k + 1) * per_texel]);
        coverage_layer[i] = if i == j { 1.0 } else { DILATED };
        dilated += usize::from(i != j);
    }
    let names: Vec<String> = (0..coeffs).map(|i| format!("T{i}")).chain(["coverage".to_string()]).collect();
    // Layer T_i: one grey channel Y, or R, G, B (channel c's coefficient i) when coloured.
    let letters: &[&str] = if channels == 1 { &["Y"] } else { &["R", "G", "B"] };
    let mut samples: Vec<(&str, &str, Vec<f32>)> = Vec::with_capacity(coeffs * channels + 1);
    for (i, name) in names[..coeffs].iter().enumerate() {
        for (c, letter) in letters.iter().enumerate() {
            let value = c * coeffs + i;
            samples.push((name, letter, (0..width * height).map(|p| transfer[p * per_texel + value] as f32).collect()));
        }
    }
    samples.push(("coverage", "Y", coverage_layer.clone()));
    let named: Vec<(&str, &str, &[f32])> = samples.iter().map(|(n, l, s)| (*n, *l, s.as_slice())).collect();
    let exr = crate::io::exr::encode_named_channels(width, height, &named).map_err(Error::LightmapEncoding)?;
    let info = LightmapInfo {
        file: lightmap.file.clone(),
        width,
        height,
        layers: names,
        texels_covered: covered.len(),
        texels_dilated: dilated,
        dilation: DILATION,
        texels_overlapping: coverage.overlapping,
        uvs: match lightmap.uvs {
            LightmapUvs::Mesh => "the mesh's UV set: OBJ vt, or glTF TEXCOORD_1 (else TEXCOORD_0)".into(),
            LightmapUvs::Atlas => {
                "a generated atlas (the mesh's own UVs ignored), written as the .glb's TEXCOORD_0".into()
            }
        },
        layout: format!(
            "one {} per coefficient i = l(l+1)+m, {coeffs} of them, and coverage.Y (1: \
             the texel centre lies in a triangle, {DILATED}: filled by dilation from a neighbour, 0: empty); texel \
             (x, y), row y from the top of the image, is the point of UV ((x+0.5)/{width}, (y+0.5)/{height})",
            if channels == 1 {
                "grey layer (channel T<i>.Y, f32)"
            } else {
                "colour layer (channels T<i>.R, T<i>.G, T<i>.B, f32: each channel's transfer, dotted with that \
                 channel's lighting)"
            }
        ),
        atlas: None,
    };
    Ok(Lightmap { exr, info, transfer, coverage: coverage_layer })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_shared_edge_covers_each_texel_once() {
        // Two triangles splitting the unit square along its diagonal, which passes through the
        // centres of the diagonal texels: each must go to exactly one triangle.
        let uvs = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        for (w, h) in [(8, 8), (7, 5), (16, 16)] {
            let c = rasterize(&uvs, &[[0, 1, 2], [0, 2, 3]], w, h);
            assert!(c.samples.iter().all(Option::is_some), "{w}x{h}: a texel is empty");
            assert_eq!(c.overlapping, 0, "{w}x{h}");
            for s in c.samples.iter().flatten() {
                assert!((s.weights.iter().sum::<f64>() - 1.0).abs() < 1e-12);
                assert!(s.weights.iter().all(|&b| b >= 0.0));
            }
            // The clockwise twin covers the same texels.
            let d = rasterize(&uvs, &[[0, 2, 1], [0, 3, 2]], w, h);
            assert!(d.samples.iter().all(Option::is_some) && d.overlapping == 0);
        }
    }

    #[test]
    fn dilation_grows_a_chart_by_its_rounds() {
        let uvs = [[0.4, 0.4], [0.6, 0.4], [0.6, 0.6], [0.4, 0.6]];
        let c = rasterize(&uvs, &[[0, 1, 2], [0, 2, 3]], 10, 10);
        let covered = c.samples.iter().filter(|s| s.is_some()).count();
        assert_eq!(covered, 4);
        let s = dilate(&c, 2);
        // A 2×2 block grown by two texels each way: 6×6.
        assert_eq!(s.iter().filter(|s| s.is_some()).count(), 36);
    }
}
