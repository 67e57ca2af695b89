//! The direction grid of the BRDF matrix: n × n cells uniform in cos θ and φ, so every cell has
//! the same solid angle (Mahajan et al. 2008, §3.2: "to preserve correct sampling on the
//! sphere, we uniformly sampled along cos θ and φ"). Samples sit at the cell midpoints in
//! cos θ and φ. Sampling uniformly in θ instead, without solid-angle weights, over-weights the
//! poles and silently lowers K.

use glam::DVec3;
use std::f64::consts::PI;

/// Which directions the BRDF matrix covers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Domain {
    /// The full sphere for both ω_i and ω_o (the paper's analytic setting, §3.1–3.3).
    Sphere,
    /// The visible hemispheres, z > 0 for both (physical BRDFs, §3.4).
    Hemisphere,
}

impl std::fmt::Display for Domain {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Domain::Sphere => "sphere",
            Domain::Hemisphere => "hemisphere",
        })
    }
}

/// An n × n grid in (cos θ, φ) over a [`Domain`]. Direction index = j·n + k with j the cos θ
/// bin (from the pole, cos θ decreasing) and k the φ bin.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Grid {
    /// Bins along cos θ and along φ.
    pub n: usize,
    /// Sphere or hemisphere.
    pub domain: Domain,
}

impl Grid {
    /// Number of directions, n².
    pub fn len(&self) -> usize {
        self.n * self.n
    }

    /// Always false for a valid grid (n ≥ 1).
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// cos θ at the midpoint of bin j, decreasing from the pole: 1 − (j+½)·h with h = 2/n on the
    /// sphere and 1/n on the hemisphere.
    pub fn cos_theta(&self, j: usize) -> f64 {
        1.0 - (j as f64 + 0.5) * self.span() / self.n as f64
    }

    /// The range of cos θ the grid covers: 2 on the sphere, 1 on the hemisphere.
    pub fn span(&self) -> f64 {
        match self.domain {
            Domain::Sphere => 2.0,
            Domain::Hemisphere => 1.0,
        }
    }

    /// φ at the midpoint of bin k: (k+½)·2π/n.
    pub fn phi(&self, k: usize) -> f64 {
        (k as f64 + 0.5) * 2.0 * PI / self.n as f64
    }

    /// The direction of bin (j, k).
    pub fn direction_jk(&self, j: usize, k: usize) -> DVec3 {
        let c = self.cos_theta(j);
        let s = (1.0 - c * c).max(0.0).sqrt();
        let (sp, cp) = self.phi(k).sin_cos();
        DVec3::new(s * cp, s * sp, c)
    }

    /// The direction of flat index j·n + k.
    pub fn direction(&self, index: usize) -> DVec3 {
        self.direction_jk(index / self.n, index % self.n)
    }

    /// Solid angle of one cell: 4π/n² (sphere) or 2π/n² (hemisphere).
    pub fn cell_solid_angle(&self) -> f64 {
        let area = match self.domain {
            Domain::Sphere => 4.0 * PI,
            Domain::Hemisphere => 2.0 * PI,
        };
        area / self.len() as f64
    }
}

/// The samples of every grid cell in the frame of a point, for integrals over the cells:
/// `sub`×`sub` directions uniform in (cos θ, φ) inside each cell (equal solid angles), so that a
/// cell's lighting is a box prefilter of the environment over the cell (point samples alias
/// bright sources), and each sample's weight, [max(cos θ, 0)] ΔΩ / sub² (the cosine when the
/// factors do not hold it). `render --shading factored` gathers the lighting at them and
/// `transfer --factors` projects the SH basis onto them: the same cells and weights, so a glossy
/// bake relit by band-limited lighting is what the factored render computes.
pub struct CellSamples {
    /// sub² samples per cell.
    pub per_cell: usize,
    /// The directions, cell after cell.
    pub dirs: Vec<DVec3>,
    /// Their weights.
    pub weights: Vec<f64>,
}

impl CellSamples {
    /// `sub`×`sub` samples in every cell of `grid`, weighted by max(cos θ, 0) when `cosine`.
    pub fn new(grid: &Grid, sub: usize, cosine: bool) -> Self {
        let (n, span) = (grid.n, grid.span());
        let dirs: Vec<DVec3> = (0..grid.len())
            .flat_map(|c| {
                let (j, k) = (c / n, c % n);
                (0..sub * sub).map(move |s| {
                    let z = 1.0 - (j as f64 + ((s / sub) as f64 + 0.5) / sub as f64) * span / n as f64;
                    let phi = (k as f64 + ((s % sub) as f64 + 0.5) / sub as f64) * 2.0 * PI / n as f64;
                    let r = (1.0 - z * z).max(0.0).sqrt();
                    DVec3::new(r * phi.cos(), r * phi.sin(), z)
                })
            })
            .collect();
        let weight = grid.cell_solid_angle() / (sub * sub) as f64;
        let weights = dirs.iter().map(|d| if cosine { d.z.max(0.0) * weight } else { weight }).collect();
        CellSamples { per_cell: sub * sub, dirs, weights }
    }

    /// The samples of cell `c`: (direction, weight).
    pub fn of_cell(&self, c: usize) -> impl Iterator<Item = (&DVec3, &f64)> {
        let r = c * self.per_cell..(c + 1) * self.per_cell;
        self.dirs[r.clone()].iter().zip(&self.weights[r])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_tile_the_domain_with_equal_solid_angle() {
        for domain in [Domain::Sphere, Domain::Hemisphere] {
            let g = Grid { n: 8, domain };
            let total = g.cell_solid_angle() * g.len() as f64;
            let want = if domain == Domain::Sphere { 4.0 * PI } else { 2.0 * PI };
            assert!((total - want).abs() < 1e-12);
            // ∫ z² dω = 4π/3 (sphere), 2π/3 (hemisphere). The midpoint rule in cos θ with bin
            // width h misses it by exactly 2π · span · h² · f''/24 (f = z², f'''' = 0), so a
            // grid in θ, or off-centre samples, would fail this.
            let g = Grid { n: 50, domain };
            let span = want / (2.0 * PI);
            let h = span / g.n as f64;
            let z2: f64 = (0..g.len()).map(|i| g.direction(i).z.powi(2)).sum::<f64>() * g.cell_solid_angle();
            let midpoint = want / 3.0 - 2.0 * PI * span * h * h * 2.0 / 24.0;
            assert!((z2 - midpoint).abs() < 1e-12, "{z2} vs {midpoint}");
            assert!((0..g.len()).all(|i| domain == Domain::Sphere || g.direction(i).z > 0.0));
        }
    }
}
