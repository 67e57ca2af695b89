//! The picture that proves an `ibl` bake: a roughness × metalness grid of spheres shaded from
//! the bake's files with the split sum ([`super::ibl`]), each above the ground truth — the same
//! glTF material integrated over every environment texel ([`super::reference`]) — and labelled
//! with two errors that say different things:
//!
//! - **bake**: the files against the split sum of the exact integrals ([`ExactSplitSum`]): what
//!   the bake itself gets wrong (resolution, the method of each level, packing, the lookups);
//! - **vs reference**: the files against the rendering equation: the bake's error and the split
//!   sum's own (the lobe taken at N = V = R, the BRDF's integral apart from the lighting's),
//!   which dominates for rough materials under a compact bright source.

use super::ibl::{ExactLobe, ExactSplitSum, IblBake, SplitSum};
use super::panel::Cell;
use super::reference::{Integrand, Reference};
use super::{render, Camera, Frame, Scene};
use crate::brdf::ggx::GgxError;
use crate::brdf::models::{GgxMicrofacet, GltfMaterial};
use crate::brdf::Brdf;
use crate::envmap::{self, EnvMap, EnvMapError, Layout};
use crate::ibl::reference::ReferenceError;
use crate::io::RgbImage;
use crate::limits::MAX_GRID_CELLS;
use crate::metrics::{compare, CompareError, Metrics};
use crate::prefilter::model::ModelError;
use crate::progress::{NoProgress, Progress};
use serde::{Deserialize, Serialize};

/// Default roughness columns: smooth to rough, on the levels of `ibl`'s default chain (a roughness
/// between two levels adds the engine's interpolation between them: `docs/ibl.md`).
pub const DEFAULT_ROUGHNESS: [f64; 5] = [0.2, 0.4, 0.6, 0.8, 1.0];
/// Default metalness rows: a dielectric and a metal.
pub const DEFAULT_METALNESS: [f64; 2] = [0.0, 1.0];

/// The materials of the grid: every roughness (columns) with every metalness (rows), one base
/// colour.
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialGrid {
    /// Perceptual roughness of each column, in (0, 1].
    pub roughness: Vec<f64>,
    /// Metalness of each row, in [0, 1].
    pub metalness: Vec<f64>,
}

/// One cell's material and the split sum's error against the reference.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct GridCell {
    /// Perceptual roughness.
    pub roughness: f64,
    /// Metalness.
    pub metalness: f64,
    /// The render from the files against the split sum of the exact integrals: the bake's error.
    pub bake: Metrics,
    /// The render from the files against the reference (the rendering equation).
    pub reference: Metrics,
}

/// The grid's renders.
#[derive(Clone, Debug)]
pub struct GridRender {
    /// The split-sum renders side by side (rows = metalness), no labels.
    pub mosaic: Frame,
    /// The panel's rows: split-sum renders above their references, labelled with material and
    /// errors ([`super::panel::layout_grid`]).
    pub rows: Vec<Vec<Cell>>,
    /// Every cell, row by row.
    pub cells: Vec<GridCell>,
}

/// Errors of the grid: its materials, and the steps of rendering it.
#[derive(Debug, thiserror::Error)]
pub enum GridError {
    /// No roughness or no metalness.
    #[error("the grid needs at least one roughness and one metalness")]
    Empty,
    /// More than [`MAX_GRID_CELLS`] cells.
    #[error(
        "{columns} × {rows} cells is more than the {MAX_GRID_CELLS} a grid renders (each twice, the reference at full cost)"
    )]
    TooManyCells {
        /// Roughness columns.
        columns: usize,
        /// Metalness rows.
        rows: usize,
    },
    /// A roughness outside (0, 1].
    #[error("grid roughness {0} must be in (0, 1] (r = 0, the mirror, has no GGX lobe)")]
    Roughness(f64),
    /// A metalness outside [0, 1].
    #[error("grid metalness {0} must be in [0, 1]")]
    Metalness(f64),
    /// The environment could not be resampled to lat-long for the exact integrals.
    #[error(transparent)]
    Resample(#[from] EnvMapError),
    /// The exact split-sum integrals could not be set up.
    #[error(transparent)]
    Exact(#[from] ReferenceError),
    /// A roughness GGX does not take.
    #[error(transparent)]
    Ggx(#[from] GgxError),
    /// The reference could not be set up.
    #[error(transparent)]
    Reference(#[from] ModelError),
    /// A cell could not be compared with its reference.
    #[error(transparent)]
    Compare(#[from] CompareError),
}

impl MaterialGrid {
    /// Checks the values and the cell count.
    pub fn check(&self) -> Result<(), GridError> {
        if self.roughness.is_empty() || self.metalness.is_empty() {
            return Err(GridError::Empty);
        }
        if self.roughness.len() * self.metalness.len() > MAX_GRID_CELLS {
            return Err(GridError::TooManyCells { columns: self.roughness.len(), rows: self.metalness.len() });
        }
        if let Some(r) = self.roughness.iter().find(|r| !(**r > 0.0 && **r <= 1.0)) {
            return Err(GridError::Roughness(*r));
        }
        if let Some(m) = self.metalness.iter().find(|m| !(0.0..=1.0).contains(*m)) {
            return Err(GridError::Metalness(*m));
        }
        Ok(())
    }
}

/// Renders every cell of `grid` in the base colour `base` through `camera`, from `bake` and as the
/// reference under `env`. Each cell's progress is one step of `progress`.
pub fn render_grid(
    grid: &MaterialGrid,
    base: [f64; 3],
    bake: &IblBake,
    env: &EnvMap,
    scene: &Scene,
    camera: &Camera,
    progress: &dyn Progress,
) -> Result<GridRender, GridError> {
    grid.check()?;
    // The exact integrals sum a lat-long map: another layout is resampled as `ibl` does it.
    let latlong = match env.layout() {
        Layout::LatLong => env.clone(),
        _ => envmap::resample(env, Layout::LatLong, 4 * bake.size(), 2 * bake.size(), 2)?,
    };
    let exact = crate::ibl::reference::Reference::new(&latlong)?;
    let irradiance = ExactLobe::new(&exact, 1.0)?;
    let lobes = grid.roughness.iter().map(|&r| ExactLobe::new(&exact, r)).collect::<Result<Vec<_>, _>>()?;
    progress.start("grid", (grid.roughness.len() * grid.metalness.len()) as u64);
    let mut rows = Vec::new();
    let mut cells = Vec::new();
    let mut mosaic_rows = Vec::new();
    for &metalness in &grid.metalness {
        let (mut split_row, mut truth_row, mut frames) = (Vec::new(), Vec::new(), Vec::new());
        for (&roughness, lobe) in grid.roughness.iter().zip(&lobes) {
            let specular = GgxMicrofacet::new(roughness)?;
            let material = GltfMaterial { base, metalness, specular };
            let split = render(scene, camera, env, &SplitSum::new(bake, material), &NoProgress);
            let exact_lighting = ExactSplitSum { specular: lobe, irradiance: &irradiance };
            let exact = render(scene, camera, env, &SplitSum::new(&exact_lighting, material), &NoProgress);
            let reference = Reference::new(env, Brdf::Gltf(material), Integrand::BrdfCosine, scene)?;
            let truth = render(scene, camera, env, &reference, &NoProgress);
            let against = |other: &Frame| compare(&split.image, &other.image, &split.mask).map(|(m, _)| m);
            let (bake_error, reference_error) = (against(&exact)?, against(&truth)?);
            let name = format!("r={roughness} m={metalness}");
            let percent = |m: &Metrics| format!("{:.2}%", 100.0 * m.rel_error);
            split_row.push(Cell {
                image: split.image.clone(),
                label: vec![
                    name.clone(),
                    format!("bake {}", percent(&bake_error)),
                    format!("ref {}", percent(&reference_error)),
                ],
            });
            truth_row.push(Cell { image: truth.image, label: vec![name, "reference".into()] });
            cells.push(GridCell { roughness, metalness, bake: bake_error, reference: reference_error });
            frames.push(split);
            progress.advance(1);
        }
        rows.push(split_row);
        rows.push(truth_row);
        mosaic_rows.push(frames);
    }
    progress.finish();
    Ok(GridRender { mosaic: mosaic(&mosaic_rows), rows, cells })
}

/// What the grid's labels say, for the lines under the picture (the font has no apostrophe).
pub fn legend() -> Vec<String> {
    vec![
        "Split-sum spheres from the bake files, each above its reference (every environment texel)".into(),
        "bake: relative RMS error against the split sum of the exact integrals (what the bake adds)".into(),
        "ref: relative RMS error against the reference (the bake and the split sum together)".into(),
    ]
}

/// Frames of one size tiled row by row, masks with them.
fn mosaic(rows: &[Vec<Frame>]) -> Frame {
    let (w, h) = (rows[0][0].image.width, rows[0][0].image.height);
    let (cols, n_rows) = (rows[0].len(), rows.len());
    let mut image = RgbImage::new(w * cols, h * n_rows);
    let mut mask = vec![false; w * cols * h * n_rows];
    for (j, row) in rows.iter().enumerate() {
        for (i, f) in row.iter().enumerate() {
            for y in 0..h {
                for x in 0..w {
                    let (mx, my) = (i * w + x, j * h + y);
                    image.set(mx, my, f.image.get(x, y));
                    mask[my * w * cols + mx] = f.mask[y * w + x];
                }
            }
        }
    }
    Frame { image, mask }
}
