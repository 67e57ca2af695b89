//! Glossy, view-dependent transfer through the in-out factorization (Mahajan, Tseng &
//! Ramamoorthi 2008, eq. 3–4: the factorization PRT uses to relight glossy objects under
//! changing lighting and view).
//!
//! In the frame F_x = R_z(φ_n)·R_y(θ_n)·R_z(−φ_n) of a vertex's normal, the shortest-arc turn
//! of +Z onto it ([`sphere::shortest_arc_frame`], [`FRAME`]), the BRDF is factored as
//! ρ(ω_i, ω_o) [max(cos θ_i, 0)] ≈ Σ_k σ_k h_k(ω_o) g_k(ω_i) (`factor-brdf`, the cosine in
//! brackets when the factors do not hold it). The outgoing radiance under distant
//! lighting L(ω) = Σ_j L_j Y_j(ω) is then
//!
//!   B(x, ω_o) = Σ_k h_k(F_xᵀ ω_o) c_k(x),   c_k(x) = Σ_j T_kj(x) L_j,
//!   T_kj(x) = σ_k ∫ V(x, ω) g_k(F_xᵀ ω) [max(cos θ, 0)] Y_j(ω) dω,
//!
//! a K × n² transfer matrix per vertex (the glossy analogue of Sloan, Kautz & Snyder 2002's
//! transfer vector, with the K terms of eq. 4 in place of their n² × n² BRDF matrix): at run
//! time K dot products with the lighting's SH per vertex, and K lookups of h_k per pixel.
//!
//! **The frame** matters although the BRDF is isotropic: c_k(x) is interpolated across each
//! triangle before the sum over k, and the terms' φ structure turns with F's twist about the
//! normal (an azimuthal frequency m turns by m·Δψ). The sum over k at one vertex does not see the
//! twist; a blend of vertices whose frames are twisted far apart does. R_z(φ_n)·R_y(θ_n) twists
//! by φ_n, which turns fast near both poles (a dark dot at the top of a ball); the shortest arc
//! twists smoothly everywhere but at n = −Z, where objects resting on the ground (prtkit's +Z up)
//! hide it.
//!
//! **The integral** runs over the factor grid's cells, as `render --shading factored` does
//! ([`CellSamples`]): one visibility ray per cell, along its centre, and `sub`² samples of
//! Y_j inside it with the cell's weights. So a bake relit by lighting of at most n bands is the
//! factored render's projection of that lighting, to the basis' interpolation — the identity
//! `tests/transfer.rs` checks. The basis is summed once in the local frame, P_cj = Σ_s w_s
//! Y_j(ω_cs); a vertex adds σ_k g_k(c) P_c over its visible cells and turns each of the K rows
//! onto its frame with one SH rotation (Y_j(F l) = Σ_i M_ji(F) Y_i(l) within a band, as the
//! diffuse integrator does): no basis evaluations per vertex.
//!
//! **Interreflections** ([`Visibility::Interreflected`]). A cell whose ray meets the front of a
//! surface y receives y's outgoing radiance, itself a dot product with the lighting: y's diffuse
//! transfer T(y) (Sloan, Kautz & Snyder 2002, eq. 9, [`super::interreflect`]). So the cell adds
//! σ_k g_k(c) W_c T_j(y) to row k, W_c = Σ_s w_s its weight, with the radiance taken constant
//! over the cell as its visibility is, and T(y) interpolated at the hit; it is added in world
//! axes, after the rows are turned. The surfaces the light comes off reflect diffusely: light
//! between two glossy surfaces is carried as if the far one were diffuse.

use super::interreflect::{cast, Outcome};
use super::visibility::Occluders;
use crate::factor::{CellSamples, Factorization, Grid};
use crate::mesh::Mesh;
use crate::sh::basis::eval_basis_dir;
use crate::sh::legendre::LegendreTable;
use crate::sh::rotate::ShRotation;
use crate::sphere;
use glam::DVec3;

/// The shading frame of glossy bakes, as the `.glb`'s extras and the manifest name it: bakes
/// without it used R_z(φ_n)·R_y(θ_n) and are not relit.
pub const FRAME: &str = "Rz(phi_n) Ry(theta_n) Rz(-phi_n)";

/// The per-vertex integrator of glossy transfer for one factorization, order and cell sampling.
pub struct Glossy {
    terms: usize,
    order: usize,
    grid: Grid,
    /// σ_k g_k(c), term-major (K × cells).
    g: Vec<f64>,
    /// P_cj = Σ_s w_s Y_j(ω_cs) in the local frame, cell-major (cells × n²).
    basis: Vec<f64>,
    /// W_c = Σ_s w_s: the cell's solid angle, times the cosine when the transport applies it.
    weights: Vec<f64>,
    /// The cells with a non-zero weight (all of them but those below the horizon when the
    /// transport applies the cosine).
    cells: Vec<usize>,
}

impl Glossy {
    /// The first `terms` terms of `f`; `cosine_in_factors`: the factorization was of
    /// ρ·max(cos θ_i, 0) (else the transport applies the cosine); SH `order` n; `sub`×`sub`
    /// samples of the basis per cell.
    pub fn new(f: &Factorization, terms: usize, cosine_in_factors: bool, order: usize, sub: usize) -> Glossy {
        let terms = terms.min(f.g.len());
        let grid = f.grid;
        let coeffs = order * order;
        let samples = CellSamples::new(&grid, sub.max(1), !cosine_in_factors);
        let table = LegendreTable::new(order - 1);
        let mut basis = vec![0.0; grid.len() * coeffs];
        let mut weights = vec![0.0; grid.len()];
        let mut y = vec![0.0; coeffs];
        let mut cells = Vec::with_capacity(grid.len());
        for (c, row) in basis.chunks_exact_mut(coeffs).enumerate() {
            let mut weighted = false;
            for (d, &w) in samples.of_cell(c) {
                if w == 0.0 {
                    continue;
                }
                weighted = true;
                weights[c] += w;
                eval_basis_dir(&table, *d, &mut y);
                for (p, yj) in row.iter_mut().zip(&y) {
                    *p += w * yj;
                }
            }
            if weighted {
                cells.push(c);
            }
        }
        let g = (0..terms).flat_map(|k| f.g[k].iter().map(move |gk| f.singular_values[k] * gk)).collect();
        Glossy { terms, order, grid, g, basis, weights, cells }
    }

    /// Terms K.
    pub fn terms(&self) -> usize {
        self.terms
    }

    /// Values per vertex, K·n² (term-major: term k holds `k·n² .. (k+1)·n²`).
    pub fn values_per_vertex(&self) -> usize {
        self.terms * self.order * self.order
    }

    /// Visibility rays per vertex (one per weighted cell).
    pub fn rays(&self) -> usize {
        self.cells.len()
    }

    /// The transfer matrix of the vertex at `position` with unit `normal` into `out`
    /// ([`Glossy::values_per_vertex`] values), in world axes, one ray per cell along its centre
    /// as `visibility` says. Returns how many cells saw the lighting. The sums run in the cells'
    /// fixed order.
    pub fn integrate(&self, position: DVec3, normal: DVec3, visibility: &Visibility, out: &mut [f64]) -> usize {
        let coeffs = self.order * self.order;
        let cells = self.grid.len();
        let frame = sphere::shortest_arc_frame(normal);
        let mut local = vec![0.0; self.terms * coeffs];
        // The light gathered off other surfaces, already in world axes (interreflected only: an
        // added zero would turn a −0 of the other bakes into +0).
        let mut gathered =
            vec![0.0; if matches!(visibility, Visibility::Interreflected { .. }) { self.terms * coeffs } else { 0 }];
        let mut radiance = vec![0.0; coeffs];
        let mut seen = 0;
        for &c in &self.cells {
            match visibility.sees(position, normal, frame * self.grid.direction(c), &mut radiance) {
                Sight::Lighting => {
                    seen += 1;
                    let p = &self.basis[c * coeffs..(c + 1) * coeffs];
                    for (k, row) in local.chunks_exact_mut(coeffs).enumerate() {
                        let gk = self.g[k * cells + c];
                        for (t, pj) in row.iter_mut().zip(p) {
                            *t += gk * pj;
                        }
                    }
                }
                // The surface's outgoing radiance L_y along the ray, taken as constant over the
                // cell: σ_k g_k(c) W_c L_y.
                Sight::Surface => {
                    for (k, row) in gathered.chunks_exact_mut(coeffs).enumerate() {
                        let gk = self.g[k * cells + c] * self.weights[c];
                        for (t, r) in row.iter_mut().zip(&radiance) {
                            *t += gk * r;
                        }
                    }
                }
                Sight::Dark => {}
            }
        }
        let rotation = ShRotation::new(frame, self.order - 1);
        for (row, world) in local.chunks_exact(coeffs).zip(out.chunks_exact_mut(coeffs)) {
            world.copy_from_slice(&rotation.apply_scalar(row));
        }
        for (world, extra) in out.iter_mut().zip(&gathered) {
            *world += extra;
        }
        seen
    }
}

/// What a glossy vertex's cell rays see.
pub enum Visibility<'a> {
    /// Nothing: every cell sees the lighting (V ≡ 1).
    None,
    /// A cell sees the lighting when its ray from position + offset·normal escapes `occluders`.
    Shadowed {
        /// The scene's BVH.
        occluders: &'a Occluders,
        /// The rays' origin offset along the normal, in the mesh's units.
        offset: f64,
    },
    /// Shadowed, and a cell whose ray meets the front of a surface of `mesh` receives that
    /// surface's outgoing radiance: its diffuse transfer `radiance` (n² values per vertex of
    /// `mesh`, as [`super::interreflect`] bakes it), interpolated at the hit (Sloan, Kautz &
    /// Snyder 2002, eq. 9, with the glossy vertex's factored BRDF in place of ρ/π).
    Interreflected {
        /// The scene's BVH.
        occluders: &'a Occluders,
        /// The rays' origin offset along the normal, in the mesh's units.
        offset: f64,
        /// The scene (the BVH's triangles).
        mesh: &'a Mesh,
        /// The outgoing radiance transfer of every vertex of `mesh`.
        radiance: &'a [f64],
    },
}

/// What one cell's ray sees.
enum Sight {
    /// The distant lighting.
    Lighting,
    /// The front of a surface, whose outgoing radiance transfer it gathered.
    Surface,
    /// Nothing that shines: the back of a surface, or any surface when only shadows are traced.
    Dark,
}

impl Visibility<'_> {
    /// What the ray from `position` (offset along `normal`) along `d` sees; for a front hit of
    /// an interreflected bake, the surface's radiance transfer is written to `radiance`.
    fn sees(&self, position: DVec3, normal: DVec3, d: DVec3, radiance: &mut [f64]) -> Sight {
        match *self {
            Visibility::None => Sight::Lighting,
            Visibility::Shadowed { occluders, offset } => {
                if occluders.occluded(position + offset * normal, d) {
                    Sight::Dark
                } else {
                    Sight::Lighting
                }
            }
            Visibility::Interreflected { occluders, offset, mesh, radiance: source } => {
                match cast(mesh, occluders, position + offset * normal, d) {
                    Outcome::Escaped => Sight::Lighting,
                    Outcome::Back => Sight::Dark,
                    Outcome::Front(hit) => {
                        radiance.fill(0.0);
                        hit.gather(&mesh.triangles, source, radiance);
                        Sight::Surface
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::factor::Domain;
    use crate::sh::basis::eval_basis_dir;

    /// A factorization with the given factors g_k (h unused here), σ_k = 1.
    fn factorization(grid: Grid, g: Vec<Vec<f64>>) -> Factorization {
        Factorization {
            singular_values: vec![1.0; g.len()],
            total_energy: g.len() as f64,
            method: crate::factor::Method::Dense,
            grid,
            h: g.clone(),
            g,
            azimuthal_frequency: Vec::new(),
        }
    }

    #[test]
    fn a_constant_factor_with_the_cosine_is_the_diffuse_transfer() {
        // g = 1/π with the cosine in the transport: T_j = (1/π) ∫ max(n·ω, 0) Y_j(ω) dω, the
        // unshadowed diffuse transfer at albedo 1, whose closed form is Â_l Y_lm(n)/π
        // (`unshadowed_exact`, checked against Ramamoorthi & Hanrahan 2001). The cell midpoint
        // rule in cos θ and φ converges to it as the grid refines.
        let order = 4;
        let normal = DVec3::new(0.3, -0.5, 0.8).normalize();
        let mut exact = vec![0.0; order * order];
        super::super::diffuse::unshadowed_exact(normal, order, 1.0, &mut exact);
        let mut errors = Vec::new();
        for n in [16, 32, 64] {
            let grid = Grid { n, domain: Domain::Hemisphere };
            let glossy = Glossy::new(
                &factorization(grid, vec![vec![1.0 / std::f64::consts::PI; grid.len()]]),
                1,
                false,
                order,
                2,
            );
            let mut t = vec![0.0; order * order];
            assert_eq!(glossy.integrate(DVec3::ZERO, normal, &Visibility::None, &mut t), grid.len());
            let err = t.iter().zip(&exact).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            errors.push(err);
        }
        eprintln!("constant factor vs Â_l Y_lm(n)/π at n = 16, 32, 64: {errors:?}");
        assert!(errors[2] < 4e-5, "{errors:?}");
        // Second order in the cell width: each halving divides the error by about 4.
        assert!(errors[1] / errors[2] > 3.0 && errors[0] / errors[1] > 3.0, "{errors:?}");
    }

    #[test]
    fn the_rows_are_in_world_axes_for_any_normal() {
        // A factor that is a lobe about the local +x axis (it has φ structure, so a wrong frame
        // or a rotation the wrong way moves it): the turned sums equal the basis evaluated at
        // the world directions F·ω_c directly.
        let grid = Grid { n: 12, domain: Domain::Hemisphere };
        let g: Vec<f64> = (0..grid.len()).map(|c| (3.0 * grid.direction(c).x).exp()).collect();
        let order = 5;
        let glossy = Glossy::new(&factorization(grid, vec![g.clone()]), 1, true, order, 1);
        let table = LegendreTable::new(order - 1);
        let mut y = vec![0.0; order * order];
        for normal in [DVec3::Z, DVec3::new(0.2, 0.9, -0.3).normalize(), DVec3::new(-0.7, 0.1, 0.1).normalize()] {
            let mut t = vec![0.0; order * order];
            glossy.integrate(DVec3::ZERO, normal, &Visibility::None, &mut t);
            let frame = sphere::shortest_arc_frame(normal);
            let mut want = vec![0.0; order * order];
            for c in 0..grid.len() {
                eval_basis_dir(&table, frame * grid.direction(c), &mut y);
                for (w, yj) in want.iter_mut().zip(&y) {
                    *w += g[c] * grid.cell_solid_angle() * yj;
                }
            }
            let err = t.iter().zip(&want).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            assert!(err < 1e-12, "normal {normal}: {err:e}");
        }
    }
}
