//! A generated lightmap atlas: UVs for a mesh that has none (or whose own are not wanted), so
//! that [`super::lightmap`] can bake it per texel.
//!
//! **Charts.** Triangles are grouped by greedy region growing: each unassigned triangle, in index
//! order, seeds a chart, which then takes, breadth first, every edge-adjacent triangle whose face
//! normal lies within [`CONE_DEGREES`] of the seed's normal n. Every triangle of a chart then
//! has n·n_f ≥ cos 60° = ½ > 0, so its orthographic projection onto the plane perpendicular to n
//! keeps its orientation and shrinks its area by at most half: the projection is one-to-one on
//! each triangle and locally across shared edges. (A cone up to 90° would keep orientation; 60°
//! leaves margin for rounding and bounds the area's shrink to 2×.) Orientation is local: a
//! chart that winds around (a strip along a knotted tube that meets itself) can overlap its own
//! projection, so each chart is rasterized alone at the atlas's scale, and one that covers a
//! texel twice is cut in two (the triangles that joined it first, and the rest) until none
//! does. Triangles
//! of zero area join any adjacent chart: they cover no texel.
//!
//! **Rectangles.** Each chart's projection is turned to its minimal-area bounding rectangle: the
//! minimal rectangle has a side along an edge of the convex hull (Freeman & Shapira 1975), so
//! every hull edge's direction is tried.
//!
//! **Scale and packing.** One world-to-texel scale s (texels per world unit) serves every chart,
//! so the texel density is uniform. A chart of w × h world units takes a box of
//! (⌈s·w⌉ + 1 + 2G) × (⌈s·h⌉ + 1 + 2G) texels, its rectangle's corner on the centre of the
//! box's texel (G, G), with [`GUTTER`] G empty texels on every side. The boxes are disjoint, so
//! the [`super::lightmap::DILATION`] ≤ G rounds that fill texels around a chart stay inside its
//! own box, and no bilinear lookup at a chart's border reads another chart's value. The boxes
//! are packed by a shelf packer (tallest first, left to right, a new
//! shelf when a row is full), and the largest s that packs into W × H is found by bisection.
//!
//! **Seams.** A vertex shared by k charts becomes k vertices (position and normal copied), each
//! with its chart's UV; triangles keep their order. Everything runs in index order (no hashing,
//! no threads): the same mesh gives the same atlas, bit for bit.

use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, VecDeque};

/// The half-angle of the cone of face normals a chart accepts around its seed's normal.
pub const CONE_DEGREES: f64 = 60.0;
/// Empty texels on every side of a chart's box: at least [`super::lightmap::DILATION`].
pub const GUTTER: usize = 2;
/// Bisection steps of the scale search (the scale is found to 2⁻⁴⁰ of its upper bound).
const SCALE_STEPS: usize = 40;

/// Why a mesh gets no atlas.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum AtlasError {
    /// Even at the smallest scale the charts' boxes do not fit.
    #[error(
        "its {charts} charts do not fit a {width}x{height} atlas: each needs at least {side}x{side} texels \
         (one texel and a gutter of {GUTTER} on each side)"
    )]
    TooManyCharts {
        /// Charts.
        charts: usize,
        /// W.
        width: usize,
        /// H.
        height: usize,
        /// The smallest box's side.
        side: usize,
    },
}

/// The manifest's account of a generated atlas (`docs/formats/transfer.md`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct AtlasInfo {
    /// Charts.
    pub charts: usize,
    /// The cone's half-angle in degrees.
    pub cone_degrees: f64,
    /// Texels per world unit (the same for every chart).
    pub texels_per_unit: f64,
    /// Empty texels on every side of a chart.
    pub gutter: usize,
    /// Texels inside the charts' boxes (gutters included).
    pub texels_in_charts: usize,
    /// The mesh's vertices.
    pub vertices_before: usize,
    /// Vertices after splitting along the seams.
    pub vertices_after: usize,
}

/// A mesh's atlas: the split mesh's vertices, triangles and UVs.
#[derive(Clone, Debug)]
pub struct Atlas {
    /// For each new vertex, the mesh's vertex it copies.
    pub vertex_of: Vec<u32>,
    /// The triangles, in the mesh's order, over the new vertices.
    pub triangles: Vec<[u32; 3]>,
    /// One UV per new vertex, in [0, 1]; (u, v) = (x/W, y/H) in texels.
    pub uvs: Vec<[f64; 2]>,
    /// The chart of each triangle.
    pub chart_of: Vec<u32>,
    /// What the manifest says of it.
    pub info: AtlasInfo,
}

/// One chart projected and turned: its triangles' corners in world units, the rectangle's
/// lower corner at the origin.
struct Chart {
    triangles: Vec<u32>,
    /// Per triangle, its three corners.
    corners: Vec<[DVec2; 3]>,
    size: DVec2,
}

/// The unit face normal (zero for a triangle of zero area).
fn face_normal(p: &[DVec3], t: &[u32; 3]) -> DVec3 {
    let [a, b, c] = t.map(|i| p[i as usize]);
    (b - a).cross(c - a).try_normalize().unwrap_or(DVec3::ZERO)
}

/// Each triangle's edge-adjacent triangles, in index order.
fn neighbours(triangles: &[[u32; 3]]) -> Vec<Vec<u32>> {
    let mut edges: Vec<([u32; 2], u32)> = triangles
        .iter()
        .enumerate()
        .flat_map(|(f, t)| (0..3).map(move |k| ([t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3])], f as u32)))
        .collect();
    edges.sort_unstable();
    let mut adjacent = vec![Vec::new(); triangles.len()];
    for run in edges.chunk_by(|a, b| a.0 == b.0) {
        for (_, f) in run {
            adjacent[*f as usize].extend(run.iter().map(|(_, g)| *g).filter(|g| g != f));
        }
    }
    for a in &mut adjacent {
        a.sort_unstable();
        a.dedup();
    }
    adjacent
}

/// Groups triangles into charts by region growing ([`CONE_DEGREES`]); returns each chart's
/// triangles, in the order they joined, and its seed's normal.
fn grow_charts(positions: &[DVec3], triangles: &[[u32; 3]]) -> Vec<(Vec<u32>, DVec3)> {
    let normals: Vec<DVec3> = triangles.iter().map(|t| face_normal(positions, t)).collect();
    let adjacent = neighbours(triangles);
    let cos_cone = CONE_DEGREES.to_radians().cos();
    let mut chart_of = vec![u32::MAX; triangles.len()];
    let mut charts = Vec::new();
    // Seeds with an area first, so that a zero-area triangle joins a neighbour's chart.
    let seeds = (0..triangles.len()).filter(|&f| normals[f] != DVec3::ZERO).chain(0..triangles.len());
    for seed in seeds {
        if chart_of[seed] != u32::MAX {
            continue;
        }
        let n = if normals[seed] == DVec3::ZERO { DVec3::Z } else { normals[seed] };
        let id = charts.len() as u32;
        let mut members = vec![seed as u32];
        chart_of[seed] = id;
        let mut queue = VecDeque::from([seed]);
        while let Some(f) = queue.pop_front() {
            for &g in &adjacent[f] {
                let g = g as usize;
                let fits = normals[g] == DVec3::ZERO || normals[g].dot(n) >= cos_cone;
                if chart_of[g] == u32::MAX && fits {
                    chart_of[g] = id;
                    members.push(g as u32);
                    queue.push_back(g);
                }
            }
        }
        charts.push((members, n));
    }
    charts
}

/// The convex hull of `points` (Andrew's monotone chain), counter-clockwise.
fn hull(points: &[DVec2]) -> Vec<DVec2> {
    let mut p = points.to_vec();
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let cross = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
    let mut h: Vec<DVec2> = Vec::with_capacity(2 * p.len());
    for pass in [p.clone(), p.iter().rev().copied().collect()] {
        let floor = h.len();
        for q in pass {
            while h.len() >= floor + 2 && cross(h[h.len() - 2], h[h.len() - 1], q) <= 0.0 {
                h.pop();
            }
            h.push(q);
        }
        h.pop();
    }
    h
}

/// Projects a chart onto the plane perpendicular to `n` and turns it to its minimal-area
/// bounding rectangle.
fn flatten(positions: &[DVec3], triangles: &[[u32; 3]], members: Vec<u32>, n: DVec3) -> Chart {
    let (t, b) = n.any_orthonormal_pair();
    let project = |i: u32| DVec2::new(positions[i as usize].dot(t), positions[i as usize].dot(b));
    let flat: Vec<[DVec2; 3]> = members.iter().map(|&f| triangles[f as usize].map(project)).collect();
    let outline = hull(&flat.iter().flatten().copied().collect::<Vec<_>>());
    // The ranges of the outline along d and across it.
    let extent = |d: DVec2| {
        let range = |f: &dyn Fn(DVec2) -> f64| {
            outline.iter().map(|&p| f(p)).fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), x| (l.min(x), h.max(x)))
        };
        (range(&|p| p.dot(d)), range(&|p| p.perp_dot(d)))
    };
    let area = |d: DVec2| {
        let ((u0, u1), (v0, v1)) = extent(d);
        (u1 - u0) * (v1 - v0)
    };
    let mut best = DVec2::X;
    for k in 0..outline.len() {
        if let Some(d) = (outline[(k + 1) % outline.len()] - outline[k]).try_normalize() {
            if area(d) < area(best) {
                best = d;
            }
        }
    }
    let ((u0, u1), (v0, v1)) = extent(best);
    let turn = |p: DVec2| DVec2::new(p.dot(best) - u0, p.perp_dot(best) - v0);
    let size = if outline.is_empty() { DVec2::ZERO } else { DVec2::new(u1 - u0, v1 - v0) };
    Chart { triangles: members, corners: flat.iter().map(|c| c.map(turn)).collect(), size }
}

/// A chart's box in texels at `scale`.
fn box_size(size: DVec2, scale: f64) -> [usize; 2] {
    [size.x, size.y].map(|s| (s * scale).ceil() as usize + 1 + 2 * GUTTER)
}

/// Shelf packing of `boxes` (W, H) into `width`×`height`: each box's lower corner in texels, or
/// `None` when they do not fit. Tallest first (ties by index), left to right.
fn pack(boxes: &[[usize; 2]], width: usize, height: usize) -> Option<Vec<[usize; 2]>> {
    let mut order: Vec<usize> = (0..boxes.len()).collect();
    order.sort_by_key(|&i| (std::cmp::Reverse(boxes[i][1]), i));
    let mut corner = vec![[0, 0]; boxes.len()];
    let (mut x, mut y, mut shelf) = (0, 0, 0);
    for i in order {
        let [w, h] = boxes[i];
        if x + w > width {
            (x, y, shelf) = (0, y + shelf, 0);
        }
        if x + w > width || y + h > height {
            return None;
        }
        corner[i] = [x, y];
        x += w;
        shelf = shelf.max(h);
    }
    Some(corner)
}

/// The largest scale whose boxes pack into `width`×`height`, and their corners.
fn fit(charts: &[Chart], width: usize, height: usize) -> Result<(f64, Vec<[usize; 2]>), AtlasError> {
    let boxes = |scale: f64| charts.iter().map(|c| box_size(c.size, scale)).collect::<Vec<_>>();
    let Some(mut corners) = pack(&boxes(0.0), width, height) else {
        return Err(AtlasError::TooManyCharts { charts: charts.len(), width, height, side: 1 + 2 * GUTTER });
    };
    let largest = charts.iter().map(|c| c.size.max_element()).fold(0.0, f64::max);
    let (mut lo, mut hi) = (0.0, if largest > 0.0 { width.max(height) as f64 / largest } else { 0.0 });
    for _ in 0..SCALE_STEPS {
        let mid = 0.5 * (lo + hi);
        match pack(&boxes(mid), width, height) {
            Some(c) => (lo, corners) = (mid, c),
            None => hi = mid,
        }
    }
    Ok((lo, corners))
}

/// Whether a chart, laid out in its box at `scale`, covers some texel twice: a chart that
/// winds around (a tube's strip of faces that meets itself) overlaps its own projection though
/// every triangle keeps its orientation.
fn folds(chart: &Chart, scale: f64) -> bool {
    let [bw, bh] = box_size(chart.size, scale);
    let origin = DVec2::splat(GUTTER as f64 + 0.5);
    let uvs: Vec<[f64; 2]> = chart
        .corners
        .iter()
        .flatten()
        .map(|&p| {
            let texel = origin + p * scale;
            [texel.x / bw as f64, texel.y / bh as f64]
        })
        .collect();
    let triangles: Vec<[u32; 3]> = (0..chart.corners.len() as u32).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
    super::lightmap::rasterize(&uvs, &triangles, bw, bh).overlapping > 0
}

impl Atlas {
    /// The atlas of the mesh (`positions`, `triangles`) in a `width`×`height` grid.
    pub fn new(positions: &[DVec3], triangles: &[[u32; 3]], width: usize, height: usize) -> Result<Atlas, AtlasError> {
        let mut groups = grow_charts(positions, triangles);
        let (charts, scale, corners) = loop {
            let charts: Vec<Chart> =
                groups.iter().map(|(members, n)| flatten(positions, triangles, members.clone(), *n)).collect();
            let (scale, corners) = fit(&charts, width, height)?;
            let folded: Vec<bool> = charts.iter().map(|c| c.triangles.len() > 1 && folds(c, scale)).collect();
            if !folded.contains(&true) {
                break (charts, scale, corners);
            }
            // A chart that covers a texel twice is cut in two: the triangles that joined it first
            // (a connected piece around the seed) and the rest, each projected along the seed's
            // normal as before.
            groups = groups
                .into_iter()
                .zip(folded)
                .flat_map(|((members, n), fold)| match fold {
                    false => vec![(members, n)],
                    true => {
                        let (first, rest) = members.split_at(members.len() / 2);
                        vec![(first.to_vec(), n), (rest.to_vec(), n)]
                    }
                })
                .collect();
        };
        let mut vertex_of = Vec::new();
        let mut uvs = Vec::new();
        let mut split = vec![[0u32; 3]; triangles.len()];
        let mut chart_of = vec![0u32; triangles.len()];
        let mut texels_in_charts = 0;
        for (id, (chart, corner)) in charts.iter().zip(&corners).enumerate() {
            let [bw, bh] = box_size(chart.size, scale);
            texels_in_charts += bw * bh;
            let origin = DVec2::new((corner[0] + GUTTER) as f64 + 0.5, (corner[1] + GUTTER) as f64 + 0.5);
            let mut copies: BTreeMap<u32, u32> = BTreeMap::new();
            for (&f, flat) in chart.triangles.iter().zip(&chart.corners) {
                chart_of[f as usize] = id as u32;
                for k in 0..3 {
                    let v = triangles[f as usize][k];
                    split[f as usize][k] = *copies.entry(v).or_insert_with(|| {
                        let texel = origin + flat[k] * scale;
                        vertex_of.push(v);
                        uvs.push([texel.x / width as f64, texel.y / height as f64]);
                        (vertex_of.len() - 1) as u32
                    });
                }
            }
        }
        let info = AtlasInfo {
            charts: charts.len(),
            cone_degrees: CONE_DEGREES,
            texels_per_unit: scale,
            gutter: GUTTER,
            texels_in_charts,
            vertices_before: positions.len(),
            vertices_after: vertex_of.len(),
        };
        Ok(Atlas { vertex_of, triangles: split, uvs, chart_of, info })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transfer::lightmap::rasterize;

    /// A unit cube of 8 shared corners and 12 triangles (outward, counter-clockwise).
    fn cube() -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let p = (0..8).map(|i| DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64)).collect();
        let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        let t = quads.iter().flat_map(|[a, b, c, d]| [[*a, *b, *c], [*a, *c, *d]]).collect();
        (p, t)
    }

    /// Asserts that the atlas's charts do not overlap in UV and that texels of two charts are
    /// more than 2·GUTTER apart, so that dilated rings never meet; returns the covered count.
    fn assert_charts_apart(atlas: &Atlas, width: usize, height: usize) -> usize {
        assert!(atlas.uvs.iter().flatten().all(|c| (0.0..=1.0).contains(c)));
        let coverage = rasterize(&atlas.uvs, &atlas.triangles, width, height);
        assert_eq!(coverage.overlapping, 0);
        let owner: Vec<Option<u32>> =
            coverage.samples.iter().map(|s| s.map(|s| atlas.chart_of[s.triangle as usize])).collect();
        let reach = 2 * GUTTER as i64;
        for y in 0..height as i64 {
            for x in 0..width as i64 {
                let Some(a) = owner[(y * width as i64 + x) as usize] else { continue };
                for (nx, ny) in (y - reach..=y + reach).flat_map(|ny| (x - reach..=x + reach).map(move |nx| (nx, ny))) {
                    if (0..width as i64).contains(&nx) && (0..height as i64).contains(&ny) {
                        let b = owner[(ny * width as i64 + nx) as usize];
                        assert!(b.is_none() || b == Some(a), "charts {a} and {b:?} meet near texel ({x}, {y})");
                    }
                }
            }
        }
        owner.iter().flatten().count()
    }

    #[test]
    fn a_cube_gets_six_charts_at_one_density() {
        let (p, t) = cube();
        let atlas = Atlas::new(&p, &t, 64, 48).unwrap();
        assert_eq!(atlas.info.charts, 6);
        // Each corner lies on three faces.
        assert_eq!(atlas.info.vertices_after, 24);
        let s = atlas.info.texels_per_unit;
        for (f, tri) in t.iter().enumerate() {
            let world =
                0.5 * (p[tri[1] as usize] - p[tri[0] as usize]).cross(p[tri[2] as usize] - p[tri[0] as usize]).length();
            let [a, b, c] = atlas.triangles[f].map(|i| DVec2::from(atlas.uvs[i as usize]) * DVec2::new(64.0, 48.0));
            let texels = 0.5 * (b - a).perp_dot(c - a).abs();
            assert!((texels / world - s * s).abs() < 1e-9 * s * s, "triangle {f}: {} vs {}", texels / world, s * s);
            assert!(atlas.vertex_of.len() == atlas.uvs.len());
            for k in 0..3 {
                assert_eq!(atlas.vertex_of[atlas.triangles[f][k] as usize], tri[k]);
            }
        }
        assert!(assert_charts_apart(&atlas, 64, 48) > 0);
    }

    #[test]
    fn a_sphere_packs_without_charts_meeting() {
        let (p, t) = crate::mesh::uv_sphere(12, 24);
        let atlas = Atlas::new(&p, &t, 128, 128).unwrap();
        assert!(atlas.info.charts > 6, "{:?}", atlas.info);
        // Each chart's normals stay in the cone: no triangle flips in UV.
        let signed = |t: &[u32; 3]| {
            let [a, b, c] = t.map(|i| DVec2::from(atlas.uvs[i as usize]));
            (b - a).perp_dot(c - a)
        };
        let first = signed(&atlas.triangles[0]).signum();
        assert!(atlas.triangles.iter().all(|t| signed(t) * first > 0.0));
        let covered = assert_charts_apart(&atlas, 128, 128);
        assert!(covered > 128 * 128 / 5, "{covered}");
        // The same atlas again, bit for bit.
        let again = Atlas::new(&p, &t, 128, 128).unwrap();
        assert_eq!(again.uvs, atlas.uvs);
    }

    #[test]
    fn too_small_a_grid_is_refused() {
        let (p, t) = cube();
        let error = Atlas::new(&p, &t, 12, 12).unwrap_err();
        assert_eq!(error, AtlasError::TooManyCharts { charts: 6, width: 12, height: 12, side: 5 });
    }
}
