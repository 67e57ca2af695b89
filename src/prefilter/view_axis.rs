//! The angular integral of a view-dependent lobe for a whole reflection map at once, in the
//! frame whose pole is the view.
//!
//! **Why it is a convolution.** ρ̂(ω; R, V) depends on the geometry of ω, R and V only: rotating
//! all three about V leaves it unchanged (for isotropic BRDFs N = normalize(R + V) turns with
//! them and ρ depends on θ_i, θ_o, φ_i − φ_o; Kajiya–Kay depends on T·ω and T·V). In a lat-long
//! grid whose pole is V, a rotation about the pole by one column maps the grid onto itself, so
//! the weight between output texel (x_o, y_o) and source texel (x, y) depends on (y_o, y,
//! d = x − x_o mod W) only: each pair of rows is a circular correlation in φ, done by FFT, the
//! same construction as the zonal filter ([`crate::envmap::zonal`]) with a kernel that depends
//! on the output row beyond R·ω. The view angle θ_o of an output texel is its polar angle in
//! this frame, so each output row has one cone θ*(θ_o) and one prepared view.
//!
//! **What is computed.** The source is the lighting rotated into the view's frame (each texel the
//! mean of point lookups of the piecewise-constant map over its footprint), on the
//! [`ConePyramid`] level a cone half the range's narrowest would be summed on (within the zonal
//! filter's size bound), [`REFINE`] times finer when the lobe is narrow against its texels
//! ([`tuning::NARROW_LOBE_TEXELS`]); output rows are computed from the first row at or before
//! `min_theta_o` to the pole −V, and
//! the reflection map's texels beyond `min_theta_o` are bilinear in that grid. The sum per output
//! row is that of [`super::angular::ConeIntegrator`]: the source texels whose centres lie in the
//! cone, each taken at its z-midpoint with its solid angle.
//!
//! **Cost.** O(H_cone·(W log W + W)) per output row, against O(W·N_cone) lobe evaluations for the
//! same row texel by texel; the lobe is evaluated once per (output row, source texel in its
//! cone) rather than once per (output texel, source texel), a half-angle lobe from its table
//! along each source row ([`super::model::HalfAngleLobe::on_view_circle`]). The kernel is even in d, so its
//! spectrum is real: the DCT-I of its half ([`EvenSpectrum`]), which scales each bin of the
//! source row's spectrum.
//!
//! **Determinism.** Each output row is one thread's fixed-order sum over its source rows.

use super::angular::ConePyramid;
use super::bright_pass::BrightPass;
use super::model::{Model, PreparedView};
use super::truncation::CutoffTable;
use super::tuning::{self, CONE_SAMPLES, LOCATOR_MAX_STEPS, REFINE, SUPERSAMPLE};
use crate::envmap::zonal::{inverse_row, row_spectra, EvenSpectrum, SubRow, TexelRule};
use crate::io::RgbImage;
use crate::limits::MAX_ZONAL_TEXELS;
use crate::sphere::latlong::bilinear_taps;
use crate::sphere::LatLong;
use glam::{DMat3, DQuat, DVec3, Vec3};
use rayon::prelude::*;
use realfft::RealFftPlanner;
use std::f64::consts::{PI, TAU};

/// The angular integral B(R) = Σ_t L_t ΔΩ_t ρ̂(ω_t; R, V) over the texels in the cone θ*(θ_o)
/// of R, for every texel of `out` whose view angle θ_o = ∠(R, V) is at least `min_theta_o`
/// (0: the whole map, as maps in angle ask; the SHRM's valid view angle for its fallback):
/// (row-major index, value). R = −V has no normal and gets zero. `bright`, the bright texels
/// split off the map the pyramid was built from, is added to the lighting in the view's frame
/// ([`BrightPass::splat`]).
pub fn integrate_in_view_frame(
    pyramid: &ConePyramid,
    model: &Model,
    cutoff: &CutoffTable,
    view: DVec3,
    min_theta_o: f64,
    out: LatLong,
    bright: Option<&BrightPass>,
) -> Vec<(usize, [f32; 3])> {
    // Over the range of view angles: the narrowest cone and the thinnest lobe.
    let (narrowest, thinnest) = (0..=CONE_SAMPLES)
        .map(|i| min_theta_o + (PI - min_theta_o) * i as f64 / CONE_SAMPLES as f64)
        .fold((PI, f64::INFINITY), |(cone, width), t| (cone.min(cutoff.at(t)), width.min(cutoff.width_at(t))));
    // The frame's grid within the zonal filter's bound: its spectra take 24 bytes a texel.
    let level = pyramid.level_within(narrowest / 2.0, MAX_ZONAL_TEXELS / (REFINE * REFINE)).image();
    let refine = if tuning::is_narrow(thinnest, level.height) { REFINE } else { 1 };
    let grid = LatLong::new(level.width * refine, level.height * refine);
    let to_world = DQuat::from_rotation_arc(DVec3::Z, view.normalize());
    let to_frame = to_world.inverse();
    let mut source = rotated(level, to_world, grid);
    if let Some(bright) = bright {
        bright.splat(&mut source, grid, to_frame);
    }
    // Output rows from the last one at or before min_theta_o: every texel beyond it is bilinear
    // between computed rows.
    let first = (0..grid.height).rev().find(|&y| grid.row_theta(y) <= min_theta_o).unwrap_or(0);
    let rows = filter_rows(&source, model, cutoff, first);
    // Row by row, each texel's direction from its row's and column's sines and cosines (those
    // of `texel_direction`, computed once), and the view angle only when there is a threshold.
    let columns: Vec<(f64, f64)> = (0..out.width).map(|x| out.column_phi(x).sin_cos()).collect();
    let read_back: Vec<Vec<(usize, [f32; 3])>> = (0..out.height)
        .into_par_iter()
        .map(|y_out| {
            let (st, ct) = out.row_theta(y_out).sin_cos();
            let mut found = Vec::with_capacity(out.width);
            for (x_out, &(sp, cp)) in columns.iter().enumerate() {
                let r = DVec3::new(st * cp, st * sp, ct);
                if min_theta_o > 0.0 && r.dot(view).clamp(-1.0, 1.0).acos() < min_theta_o {
                    continue;
                }
                let (px, py) = grid.position(to_frame * r);
                let mut v = [0.0f64; 3];
                for (t, w) in bilinear_taps(grid.width, grid.height, px - 0.5, py - 0.5, true) {
                    // θ' > min_theta_o puts both tap rows at or after `first` (up to rounding).
                    let (x, y) = (t % grid.width, (t / grid.width).max(first));
                    let p = rows[(y - first) * grid.width + x];
                    for c in 0..3 {
                        v[c] += w * p[c];
                    }
                }
                found.push((y_out * out.width + x_out, v.map(|c| c as f32)));
            }
            found
        })
        .collect();
    read_back.into_iter().flatten().collect()
}

/// `map` seen from the frame `to_world` takes to world space, on `grid`: texel (x, y) of the
/// result is the mean of n² point lookups of the piecewise-constant `map` at points spread over
/// its footprint, rotated (its parent texel when nothing moves and the grid splits the map's
/// texels); n keeps [`SUPERSAMPLE`] lookups per axis of a texel of `map` (3 on a grid twice as
/// fine).
fn rotated(map: &RgbImage, to_world: DQuat, grid: LatLong) -> RgbImage {
    let src = LatLong::new(map.width, map.height);
    let k = grid.width / src.width;
    if to_world.abs_diff_eq(DQuat::IDENTITY, 1e-15) && grid == LatLong::new(k * src.width, k * src.height) {
        // Nothing moves and the grid splits each texel of the map into k × k: every lookup of a
        // texel lands in its parent, so the box filter is the parent's value (a +Z view's
        // refined frame): a copy, not a lookup per texel.
        return RgbImage::from_fn(grid.width, grid.height, |x, y| map.pixels[(y / k) * src.width + x / k]);
    }
    let mut out = RgbImage::new(grid.width, grid.height);
    let n = (SUPERSAMPLE * src.height).div_ceil(grid.height).max(1);
    let k = n as f64;
    // The lookups lie on a grid n times finer than `grid`: (sin, cos) of φ per sub-column, of θ
    // per sub-row, so a lookup's direction in the map's frame is sin θ·a(φ) + cos θ·M ẑ with
    // a(φ) = cos φ·M x̂ + sin φ·M ŷ per sub-column.
    let sub = |t: usize, i: usize| t as f64 + (i as f64 + 0.5) / k;
    let m = DMat3::from_quat(to_world);
    let columns: Vec<Vec3> = (0..grid.width * n)
        .map(|c| {
            let (sp, cp) = (TAU * sub(c / n, c % n) / grid.width as f64).sin_cos();
            (cp * m.x_axis + sp * m.y_axis).as_vec3()
        })
        .collect();
    let cells = TexelLocator::new(src);
    out.pixels.par_chunks_mut(grid.width).enumerate().for_each(|(y, row)| {
        let mut sums = vec![[0.0f64; 3]; grid.width];
        for j in 0..n {
            let (st, ct) = (PI * sub(y, j) / grid.height as f64).sin_cos();
            let (st, pole) = (st as f32, (ct * m.z_axis).as_vec3());
            // Neighbouring lookups along a sub-row fall in the same texel or the next one: each
            // starts from the last one's texel.
            let mut at = None;
            for (c, a) in columns.iter().enumerate() {
                let texel = cells.locate(st * *a + pole, at);
                at = Some(texel);
                let p = map.pixels[texel.1 * src.width + texel.0];
                let s = &mut sums[c / n];
                for ch in 0..3 {
                    s[ch] += p[ch] as f64;
                }
            }
        }
        for (px, s) in row.iter_mut().zip(&sums) {
            *px = s.map(|v| (v / (k * k)) as f32);
        }
    });
    out
}

/// Which texel of a lat-long grid a direction falls in, exactly against the texels' edges:
/// row y holds cos((y + 1)Δθ) < z ≤ cos(yΔθ), column x the azimuths [xΔφ, (x + 1)Δφ), tested by
/// the sign of the cross product with each edge's direction. From a nearby texel it walks to
/// the right one by comparisons alone; far away (or by a pole, where columns are thin) it
/// takes the angles. The rotation into a view's frame makes millions of lookups a map
/// (Grace into a 256×128 frame: 36 a texel), and atan2 and acos were most of their time.
struct TexelLocator {
    grid: LatLong,
    /// cos(yΔθ), y = 0..=H.
    row_edges: Vec<f32>,
    /// (cos, sin) of xΔφ, x = 0..=W.
    column_edges: Vec<(f32, f32)>,
}

impl TexelLocator {
    fn new(grid: LatLong) -> Self {
        let row_edges = (0..=grid.height).map(|y| (PI * y as f64 / grid.height as f64).cos() as f32).collect();
        let column_edges = (0..=grid.width)
            .map(|x| {
                let (s, c) = (TAU * x as f64 / grid.width as f64).sin_cos();
                (c as f32, s as f32)
            })
            .collect();
        TexelLocator { grid, row_edges, column_edges }
    }

    /// The texel (x, y) of direction `d`, walking from `near` when given.
    #[inline]
    fn locate(&self, d: Vec3, near: Option<(usize, usize)>) -> (usize, usize) {
        let (w, h) = (self.grid.width, self.grid.height);
        let Some((mut x, mut y)) = near else { return self.by_angles(d) };
        let mut steps = 0;
        while y > 0 && d.z > self.row_edges[y] {
            y -= 1;
            steps += 1;
        }
        while y + 1 < h && d.z <= self.row_edges[y + 1] {
            y += 1;
            steps += 1;
        }
        // cross(e, d) = e.x d.y − e.y d.x ≥ 0 when d lies at or after edge e (within π of it).
        let after = |x: usize| {
            let (c, s) = self.column_edges[x];
            c * d.y - s * d.x >= 0.0
        };
        while !after(x) {
            x = (x + w - 1) % w;
            steps += 1;
            if steps > LOCATOR_MAX_STEPS {
                return self.by_angles(d);
            }
        }
        while after(x + 1) {
            x = (x + 1) % w;
            steps += 1;
            if steps > LOCATOR_MAX_STEPS {
                return self.by_angles(d);
            }
        }
        if steps > LOCATOR_MAX_STEPS {
            return self.by_angles(d);
        }
        (x, y)
    }

    /// The texel from the direction's angles.
    fn by_angles(&self, d: Vec3) -> (usize, usize) {
        self.grid.texel_of(d.as_dvec3())
    }
}

/// Rows `first..H` of the angular integral on `source`'s grid, the view at its pole.
fn filter_rows(source: &RgbImage, model: &Model, cutoff: &CutoffTable, first: usize) -> Vec<[f64; 3]> {
    let mut planner = RealFftPlanner::<f64>::new();
    let rows = RowFilter::new(source, model, cutoff, &mut planner);
    let even = EvenSpectrum::new(&mut planner, source.width);
    (first..source.height)
        .into_par_iter()
        .map_init(|| even.clone(), |even, y| rows.row(even, y))
        .flatten_iter()
        .collect()
}

/// What every output row of [`filter_rows`] reads: the source rows' spectra and geometry.
struct RowFilter<'a> {
    model: &'a Model,
    cutoff: &'a CutoffTable,
    grid: LatLong,
    /// W/2 + 1.
    bins: usize,
    /// Analytic models are grey: one kernel and one transform per pair of rows.
    channels: usize,
    inverse: std::sync::Arc<dyn realfft::ComplexToReal<f64>>,
    /// Every source row's spectra, [y][channel][m].
    spectra: Vec<realfft::num_complex::Complex<f64>>,
    /// Each source row's node: the midpoint rule of the cone sums (z-midpoint, exact solid angle).
    nodes: Vec<SubRow>,
    /// Each source row's centre θ with its sine and cosine (the cone test), and its texels'
    /// solid angle.
    centres: Vec<(f64, f64, f64, f64)>,
    /// sin and cos of the column offsets d·2π/W.
    sin_d: Vec<f64>,
    cos_d: Vec<f64>,
}

impl<'a> RowFilter<'a> {
    fn new(source: &RgbImage, model: &'a Model, cutoff: &'a CutoffTable, planner: &mut RealFftPlanner<f64>) -> Self {
        let (width, height) = (source.width, source.height);
        let grid = LatLong::new(width, height);
        let forward = planner.plan_fft_forward(width);
        let (sin_d, cos_d): (Vec<f64>, Vec<f64>) =
            (0..width).map(|d| (d as f64 * TAU / width as f64).sin_cos()).unzip();
        let centres = (0..height)
            .map(|y| {
                let theta = grid.row_theta(y);
                let (s, c) = theta.sin_cos();
                (theta, s, c, grid.row_solid_angle(y))
            })
            .collect();
        RowFilter {
            model,
            cutoff,
            grid,
            bins: width / 2 + 1,
            channels: if model.brdf().is_rgb() { 3 } else { 1 },
            inverse: planner.plan_fft_inverse(width),
            spectra: row_spectra(source, &*forward, |_| true),
            nodes: (0..height).map(|y| TexelRule::midpoint().sub_rows(grid, y)[0]).collect(),
            centres,
            sin_d,
            cos_d,
        }
    }

    /// Output row `y_out`: per source row in the cone, the spectrum of its kernel times the
    /// row's spectrum, summed, and one inverse transform per channel.
    fn row(&self, even: &mut EvenSpectrum, y_out: usize) -> Vec<[f64; 3]> {
        let (width, bins, channels) = (self.grid.width, self.bins, self.channels);
        let theta_r = self.grid.row_theta(y_out);
        let (s_r, z_r) = theta_r.sin_cos();
        let mut row = vec![[0.0; 3]; width];
        // R = −V has no normal: its row stays zero.
        let Some(prepared) = self.model.prepare_view(DVec3::new(s_r, 0.0, z_r), DVec3::Z) else {
            return row;
        };
        let theta_star = self.cutoff.at(theta_r);
        let cos_star = if theta_star >= PI { f64::NEG_INFINITY } else { theta_star.cos() };
        let mut kernel = vec![vec![0.0; bins]; channels];
        let mut spectrum = vec![vec![0.0; bins]; channels];
        let mut acc = [(); 3].map(|_| self.inverse.make_input_vec());
        for ((&(theta, st, ct, solid_angle), node), src) in
            self.centres.iter().zip(&self.nodes).zip(self.spectra.chunks_exact(3 * bins))
        {
            if (theta - theta_r).abs() > theta_star {
                continue;
            }
            // The cone test on the texel's centre, as the cone sums do. cos d falls with d: the
            // row's texels in the cone are d < end.
            let end = self.cos_d[..bins].iter().position(|&c| ct * z_r + st * s_r * c < cos_star).unwrap_or(bins);
            if end == 0 {
                continue;
            }
            self.kernel(&prepared, node, solid_angle, end, &mut kernel);
            for (k, out) in kernel.iter().zip(spectrum.iter_mut()) {
                even.transform(k, out);
            }
            for (c, acc) in acc.iter_mut().enumerate() {
                let k = &spectrum[c.min(channels - 1)];
                // Σ_x L(x) k(x − x_o) is the inverse transform of L̂·conj(k̂), k̂ real.
                for ((a, l), k) in acc.iter_mut().zip(&src[c * bins..(c + 1) * bins]).zip(k) {
                    *a += l * k;
                }
            }
        }
        let mut out = self.inverse.make_output_vec();
        let mut scratch = self.inverse.make_scratch_vec();
        for (c, acc) in acc.iter_mut().enumerate() {
            inverse_row(&*self.inverse, acc, &mut out, &mut scratch);
            for (p, v) in row.iter_mut().zip(&out) {
                p[c] = *v;
            }
        }
        row
    }

    /// The kernel between an output row (`prepared`) and the source row of `node`, over the
    /// offsets d < `end` in its cone, into `kernel` (per channel). R and V lie in the xz-plane,
    /// and ρ̂ is even under the mirror y → −y (isotropy with bilateral symmetry; Kajiya–Kay
    /// through T·ω and T·V), so the kernel is even in d: its half d = 0..=W/2 is evaluated (zero
    /// past the cone), and its spectrum is real.
    fn kernel(&self, prepared: &PreparedView, node: &SubRow, solid_angle: f64, end: usize, kernel: &mut [Vec<f64>]) {
        let (cos_d, sin_d) = (&self.cos_d, &self.sin_d);
        kernel.iter_mut().for_each(|k| k.fill(0.0));
        match self.model.half_angle_lobe() {
            Some(lobe) => {
                // Grey: one channel computed, copied to any other.
                let rho_hat = lobe.on_view_circle(prepared, node.z, node.sin_theta);
                let (first, rest) = kernel.split_at_mut(1);
                for ((k, &c), &s) in first[0][..end].iter_mut().zip(cos_d).zip(sin_d) {
                    *k = solid_angle * rho_hat(c, s);
                }
                for k in rest {
                    k[..end].copy_from_slice(&first[0][..end]);
                }
            }
            None => {
                for d in 0..end {
                    let l = DVec3::new(node.sin_theta * cos_d[d], node.sin_theta * sin_d[d], node.z);
                    let v = self.model.rho_hat_prepared(prepared, l);
                    for (k, v) in kernel.iter_mut().zip(v) {
                        k[d] = solid_angle * v;
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::brdf::Brdf;
    use crate::envmap::EnvMap;
    use crate::prefilter::angular::ConeIntegrator;

    fn model() -> Model {
        Model::new(Brdf::parse("torrance-sparrow:sigma=0.2").unwrap(), true).unwrap()
    }

    /// A smooth map with gradients along every axis (so a rotation the wrong way round, or a
    /// correlation run backwards, moves its values).
    fn smooth_map(width: usize, height: usize) -> EnvMap {
        let grid = LatLong::new(width, height);
        let mut image = RgbImage::new(width, height);
        for y in 0..height {
            for x in 0..width {
                let d = grid.texel_direction(x, y);
                let v = 2.0 + 0.8 * d.x - 0.5 * d.y + 0.6 * d.z + 0.4 * d.x * d.z;
                image.pixels[y * width + x] = [v as f32, (0.5 * v) as f32, (3.0 - v) as f32];
            }
        }
        EnvMap::latlong(image).unwrap()
    }

    /// Per texel, the cone sum of [`ConeIntegrator::integrate_reference`] on `env` (every
    /// texel, every direction from trigonometry).
    fn texel_by_texel(
        env: &EnvMap,
        rule: TexelRule,
        model: &Model,
        cutoff: &CutoffTable,
        view: DVec3,
        out: LatLong,
    ) -> Vec<[f64; 3]> {
        let cone = ConeIntegrator::new(env).unwrap().with_rule(rule);
        (0..out.width * out.height)
            .map(|i| {
                let r = out.texel_direction(i % out.width, i / out.width);
                match model.prepare_view(r, view) {
                    Some(p) => cone.integrate_reference(r, cutoff.at(r.dot(view).clamp(-1.0, 1.0).acos()), |l| {
                        model.rho_hat_prepared(&p, l)
                    }),
                    None => [0.0; 3],
                }
            })
            .collect()
    }

    #[test]
    fn the_texel_locator_walks_to_the_texel_the_angles_give() {
        let grid = LatLong::new(64, 32);
        let cells = TexelLocator::new(grid);
        let mut rng = crate::rng::SplitMix64::new(7);
        let (mut walked, mut checked) = (0, 0);
        for _ in 0..20_000 {
            let z = 2.0 * rng.next_f64() - 1.0;
            let phi = TAU * rng.next_f64();
            let s = (1.0 - z * z).sqrt();
            let d = DVec3::new(s * phi.cos(), s * phi.sin(), z);
            // Away from the edges, where the single-precision walk and the angles may disagree.
            let (fx, fy) = grid.position(d);
            let margin = 1e-3;
            if (fx - fx.round()).abs() < margin || (fy - fy.round()).abs() < margin {
                continue;
            }
            let want = grid.texel_of(d);
            let d = d.as_vec3();
            // From the texel itself, its neighbours, one two columns away, and a far one.
            let (x, y) = want;
            let (w, h) = (grid.width, grid.height);
            for near in [
                (x, y),
                ((x + 1) % w, y),
                ((x + w - 1) % w, y.saturating_sub(1)),
                ((x + 2) % w, (y + 1).min(h - 1)),
                ((x + w / 2) % w, h - 1 - y),
            ] {
                assert_eq!(cells.locate(d, Some(near)), want, "from {near:?}");
                walked += usize::from(near != want);
            }
            checked += 1;
        }
        assert!(checked > 10_000 && walked > 40_000, "{checked} directions, {walked} walks");
        // At a pole every column's edge test is zero: the walk gives up and takes the angles.
        assert_eq!(cells.locate(Vec3::Z, Some((5, 0))).1, 0);
        assert_eq!(cells.locate(-Vec3::Z, Some((5, 31))).1, 31);
    }

    #[test]
    fn the_row_convolutions_equal_the_texel_by_texel_sum() {
        // View at the pole and the output on the view frame's own grid: no resampling either
        // way (the frame's grid halves every texel of the map, which copies it exactly), so the
        // FFT correlations must reproduce the direct sum on that grid to rounding.
        let model = model();
        let cutoff = CutoffTable::of_model(&model, 1e-4, 33);
        let env = smooth_map(32, 16);
        let pyramid = ConePyramid::new(&env).unwrap();
        let out = LatLong::new(64, 32);
        let min_theta_o = 1.2;
        let fast = integrate_in_view_frame(&pyramid, &model, &cutoff, DVec3::Z, min_theta_o, out, None);
        // The map with each texel split 2 × 2, made here rather than by `rotated`, whose copy of
        // it is under test too.
        let fine = EnvMap::latlong(RgbImage::from_fn(out.width, out.height, |x, y| {
            env.image().pixels[(y / 2) * env.image().width + x / 2]
        }))
        .unwrap();
        let direct = texel_by_texel(&fine, TexelRule::midpoint(), &model, &cutoff, DVec3::Z, out);
        let expected = (0..out.height).filter(|&y| out.row_theta(y) >= min_theta_o).count() * out.width;
        assert_eq!(fast.len(), expected);
        for &(i, v) in &fast {
            for c in 0..3 {
                let (a, b) = (v[c] as f64, direct[i][c]);
                // A texel centre on the cone's edge may fall either side by rounding; its weight
                // is within the 10⁻⁴ of the lobe the cone leaves out.
                assert!((a - b).abs() <= 1e-4 * b.abs().max(1e-3), "texel {i} channel {c}: {a} against {b}");
            }
        }
    }

    #[test]
    fn a_tilted_view_matches_the_texel_by_texel_sum_on_a_smooth_map() {
        // The lighting rotated into the view's frame and the output read back bilinearly: on a
        // smooth map both resamplings are within a fraction of a per cent of the direct sum.
        let model = model();
        let cutoff = CutoffTable::of_model(&model, 1e-4, 33);
        let env = smooth_map(64, 32);
        let pyramid = ConePyramid::new(&env).unwrap();
        let out = LatLong::new(48, 24);
        let view = DVec3::new(0.5, -0.3, 0.4).normalize();
        let min_theta_o = 1.5;
        let fast = integrate_in_view_frame(&pyramid, &model, &cutoff, view, min_theta_o, out, None);
        let direct = texel_by_texel(&env, TexelRule::new(4).unwrap(), &model, &cutoff, view, out);
        let expected = (0..out.width * out.height)
            .filter(|&i| out.texel_direction(i % out.width, i / out.width).dot(view).acos() >= min_theta_o)
            .count();
        assert_eq!(fast.len(), expected);
        let mut worst = 0.0f64;
        for &(i, v) in &fast {
            for c in 0..3 {
                let (a, b) = (v[c] as f64, direct[i][c]);
                if b.abs() > 1e-3 {
                    worst = worst.max((a - b).abs() / b.abs());
                }
            }
        }
        assert!(worst < 0.01, "worst relative difference {worst}");
    }
}
