//! Cube maps in the engine convention: the Vulkan/KTX2 face order and orientation, texel ↔
//! direction both ways, exact texel solid angles, mip chains, and the glTF ↔ prtkit frame.
//!
//! ## Faces and orientation
//!
//! Faces are stored +X, −X, +Y, −Y, +Z, −Z, each with orientation `rd` (row 0 at the top,
//! columns left to right): KTX 2.0 specification, §3.7 "faceCount" and Appendix "Cubemap
//! Orientation", which defines the layout as the one the Vulkan and OpenGL cube samplers read
//! (Vulkan specification, "Cube Map Face Selection and Transformations": the major axis selects
//! the face, then s = ½(s_c/|m_a| + 1), t = ½(t_c/|m_a| + 1) with (s_c, t_c) = (−r_z, −r_y) on +X,
//! (r_z, −r_y) on −X, (r_x, r_z) on +Y, (r_x, −r_z) on −Y, (r_x, −r_y) on +Z, (−r_x, −r_y) on −Z).
//! Inverting that table, the texel in row r, column c of an n×n face, with s = 2(c + ½)/n − 1 and
//! t = 2(r + ½)/n − 1, looks along
//!
//!   +X (1, −t, −s)   −X (−1, −t, s)   +Y (s, 1, t)   −Y (s, −1, −t)   +Z (s, −t, 1)   −Z (−s, −t, −1).
//!
//! These are directions in the **cube frame**, the frame a shader samples in. It is glTF's world
//! frame (+Y up), so an engine samples with its world-space direction. (The KTX appendix calls the
//! sampler's frame left-handed because it pictures the faces as seen from inside; the map from
//! directions to texels above is all that matters here, and it is what samplers implement.)
//!
//! ## Frames
//!
//! prtkit's frame is +Z up (`docs/conventions.md`); glTF's is +Y up. [`WORLD_FROM_PRTKIT`] is the
//! proper rotation (det +1, right-handed to right-handed) by −90° about X that takes prtkit's
//! +Z to +Y and keeps +X: (x, y, z) ↦ (x, z, −y). So prtkit's +X lands on face +X, its zenith on
//! +Y, and its +Y on −Z.
//!
//! Texel solid angles are exact: they come from prtkit's environment-map geometry
//! (`envmap`'s cube faces share this orientation within a face), which integrates the area element
//! of the unit-distance face plane in closed form.

use crate::envmap::{EnvMap, Face, FACES};
use crate::io::gpu_format::{Texture, TextureShape};
use crate::io::RgbImage;
use crate::limits::MAX_CUBE_FACE_SIZE;
use crate::sphere::latlong::bilinear_taps;
use glam::{DMat3, DVec3};
use rayon::prelude::*;

/// World (glTF, +Y up) from prtkit (+Z up): (x, y, z) ↦ (x, z, −y). A rotation: det = +1.
pub const WORLD_FROM_PRTKIT: DMat3 = DMat3::from_cols(
    DVec3::new(1.0, 0.0, 0.0),  // prtkit +X → world +X
    DVec3::new(0.0, 0.0, -1.0), // prtkit +Y → world −Z
    DVec3::new(0.0, 1.0, 0.0),  // prtkit +Z (up) → world +Y (up)
);

/// prtkit from world: the inverse (transpose) of [`WORLD_FROM_PRTKIT`].
pub const PRTKIT_FROM_WORLD: DMat3 =
    DMat3::from_cols(DVec3::new(1.0, 0.0, 0.0), DVec3::new(0.0, 0.0, 1.0), DVec3::new(0.0, -1.0, 0.0));

/// Errors about cube-map geometry.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum CubeError {
    /// A face size of 0 or above [`MAX_CUBE_FACE_SIZE`].
    #[error("a cube face must be between 1 and {MAX_CUBE_FACE_SIZE} texels wide, got {0}")]
    Size(usize),
    /// A level cannot be halved (odd size).
    #[error("a {0}² cube face cannot be halved into a mip level")]
    Odd(usize),
    /// A mip chain whose level sizes do not halve.
    #[error("mip level {level} is {size}² but must be {expected}² (each level halves the previous)")]
    Chain {
        /// Level index.
        level: usize,
        /// Its face size.
        size: usize,
        /// The size it must have.
        expected: usize,
    },
    /// An empty mip chain.
    #[error("a mip chain needs at least one level")]
    Empty,
}

/// The cube-frame direction (not normalized) at face coordinates (s, t) ∈ [−1, 1]² (the
/// crate's one face table, [`Face::direction`]).
#[inline]
pub fn face_direction(face: Face, s: f64, t: f64) -> DVec3 {
    face.direction(s, t)
}

/// Face coordinate of texel `k` of an n-texel row or column: 2(k + ½)/n − 1.
#[inline]
pub fn texel_coordinate(size: usize, k: usize) -> f64 {
    2.0 * (k as f64 + 0.5) / size as f64 - 1.0
}

/// The unit cube-frame direction through the centre of texel (row, col) of an n×n face.
pub fn texel_direction(face: Face, size: usize, row: usize, col: usize) -> DVec3 {
    face_direction(face, texel_coordinate(size, col), texel_coordinate(size, row)).normalize()
}

/// The face a cube-frame direction selects and its face coordinates (s, t) ∈ [−1, 1]², by the
/// Vulkan major-axis rule (ties go to X, then Y): [`crate::envmap::select_face`].
#[inline]
pub fn face_coordinates(dir: DVec3) -> (Face, f64, f64) {
    crate::envmap::select_face(dir)
}

/// The texel (face, row, column) of an n×n cube that contains a cube-frame direction.
pub fn texel_of(dir: DVec3, size: usize) -> (Face, usize, usize) {
    let (face, s, t) = face_coordinates(dir);
    let index = |c: f64| (((c + 1.0) * 0.5 * size as f64).floor().max(0.0) as usize).min(size - 1);
    (face, index(t), index(s))
}

/// Exact solid angles of the n×n texels of one face, row-major (the same for all six faces).
/// They sum to 4π/6 per face.
pub fn texel_solid_angles(size: usize) -> Result<Vec<f64>, CubeError> {
    check_size(size)?;
    // prtkit's environment-map geometry holds the closed form (the face-plane area element
    // integrated over the texel); it is reached through a six-face map of this size.
    let faces = (0..6).map(|_| RgbImage::new(size, size)).collect();
    let geometry = EnvMap::from_faces(faces).map_err(|_| CubeError::Size(size))?;
    Ok((0..size * size)
        .map(|i| geometry.texel_geometry(0, i % size, i / size).map_or(0.0, |(_, omega)| omega))
        .collect())
}

fn check_size(size: usize) -> Result<(), CubeError> {
    if size == 0 || size > MAX_CUBE_FACE_SIZE {
        return Err(CubeError::Size(size));
    }
    Ok(())
}

/// A cube map: six n×n faces of linear RGB, in the order and orientation above.
#[derive(Clone, Debug, PartialEq)]
pub struct CubeMap {
    size: usize,
    /// Interleaved RGB, face-major then row-major: the layout of one KTX2 level.
    data: Vec<f32>,
}

impl CubeMap {
    /// A black cube of n×n faces.
    pub fn new(size: usize) -> Result<Self, CubeError> {
        check_size(size)?;
        Ok(CubeMap { size, data: vec![0.0; 6 * size * size * 3] })
    }

    /// A cube whose texel values are `f(direction)` at the texel centres (cube frame), computed
    /// in parallel over rows.
    pub fn from_fn(size: usize, f: impl Fn(DVec3) -> [f32; 3] + Sync) -> Result<Self, CubeError> {
        let mut cube = CubeMap::new(size)?;
        cube.data.par_chunks_mut(size * 3).enumerate().for_each(|(face_row, row)| {
            let (face, r) = (FACES[face_row / size], face_row % size);
            for (c, px) in row.chunks_exact_mut(3).enumerate() {
                px.copy_from_slice(&f(texel_direction(face, size, r, c)));
            }
        });
        Ok(cube)
    }

    /// Resamples an environment map (any layout, prtkit's frame) into a cube whose frame is
    /// `env_from_cube` applied to the cube directions ([`PRTKIT_FROM_WORLD`] for glTF's +Y up,
    /// the identity to keep prtkit's frame). Each texel is the mean of `supersample`² bilinear
    /// lookups weighted by their solid angle, dω ∝ (1 + s² + t²)^(−3/2).
    pub fn resample(env: &EnvMap, size: usize, supersample: usize, env_from_cube: DMat3) -> Result<Self, CubeError> {
        let mut cube = CubeMap::new(size)?;
        let k = supersample.max(1);
        // Sub-sample (i, j) of column c sits at face coordinate 2(c + (i + ½)/k)/n − 1.
        let sub = |texel: usize, i: usize| 2.0 * (texel as f64 + (i as f64 + 0.5) / k as f64) / size as f64 - 1.0;
        cube.data.par_chunks_mut(size * 3).enumerate().for_each_init(
            || (Vec::with_capacity(size * k * k), Vec::with_capacity(size * k * k), vec![[0.0f32; 3]; size * k * k]),
            |(dirs, weights, values), (face_row, row)| {
                let (face, r) = (FACES[face_row / size], face_row % size);
                // The row's lookups at once (`EnvMap::lookup_many` runs them in SIMD lanes),
                // texel by texel, k × k each. A face's directions are affine in (s, t).
                let along_s = env_from_cube * (face_direction(face, 1.0, 0.0) - face_direction(face, 0.0, 0.0));
                dirs.clear();
                weights.clear();
                for c in 0..size {
                    for j in 0..k {
                        let t = sub(r, j);
                        let start = env_from_cube * face_direction(face, 0.0, t);
                        for i in 0..k {
                            let s = sub(c, i);
                            let d = start + s * along_s;
                            dirs.push([d.x as f32, d.y as f32, d.z as f32]);
                            let q = 1.0 + s * s + t * t;
                            weights.push(1.0 / (q * q.sqrt()));
                        }
                    }
                }
                env.lookup_many(dirs, values);
                let texels = values.chunks_exact(k * k).zip(weights.chunks_exact(k * k));
                for (px, (values, weights)) in row.chunks_exact_mut(3).zip(texels) {
                    let (mut sum, mut weight) = ([0.0f64; 3], 0.0);
                    for (v, &w) in values.iter().zip(weights.iter()) {
                        for ch in 0..3 {
                            sum[ch] += w * v[ch] as f64;
                        }
                        weight += w;
                    }
                    for ch in 0..3 {
                        px[ch] = (sum[ch] / weight) as f32;
                    }
                }
            },
        );
        Ok(cube)
    }

    /// The face size n.
    pub fn size(&self) -> usize {
        self.size
    }

    fn offset(&self, face: Face, row: usize, col: usize) -> usize {
        ((face.index() * self.size + row) * self.size + col) * 3
    }

    /// The texel at (face, row, column).
    #[inline]
    pub fn get(&self, face: Face, row: usize, col: usize) -> [f32; 3] {
        let o = self.offset(face, row, col);
        [self.data[o], self.data[o + 1], self.data[o + 2]]
    }

    /// Sets the texel at (face, row, column).
    pub fn set(&mut self, face: Face, row: usize, col: usize, rgb: [f32; 3]) {
        let o = self.offset(face, row, col);
        self.data[o..o + 3].copy_from_slice(&rgb);
    }

    /// All texels as interleaved RGB, faces in order, rows top to bottom.
    pub fn texels(&self) -> &[f32] {
        &self.data
    }

    /// The cube as texture data for the KTX2 and DDS writers (`crate::io::texture`): one level,
    /// three channels.
    pub fn as_texture(&self) -> Texture<'_> {
        Texture { shape: TextureShape::Cube { size: self.size }, channels: 3, levels: vec![&self.data] }
    }

    /// Mutable interleaved texels (same layout).
    pub fn texels_mut(&mut self) -> &mut [f32] {
        &mut self.data
    }

    /// The value of the texel containing a cube-frame direction (no filtering).
    pub fn lookup_nearest(&self, dir: DVec3) -> [f32; 3] {
        let (face, row, col) = texel_of(dir, self.size);
        self.get(face, row, col)
    }

    /// Bilinear lookup within the face a cube-frame direction selects, clamped at the face's
    /// edges (a sampler without seamless cube filtering; the seam-free bake makes the texels on
    /// either side of an edge agree, so the two differ little).
    pub fn lookup_bilinear(&self, dir: DVec3) -> [f32; 3] {
        let (face, s, t) = face_coordinates(dir);
        let n = self.size as f64;
        // Texel-centre coordinates within the face, as `EnvMap::lookup` takes them on faces.
        let (fx, fy) = ((s + 1.0) * 0.5 * n - 0.5, (t + 1.0) * 0.5 * n - 0.5);
        let mut out = [0.0f32; 3];
        for (i, w) in bilinear_taps(self.size, self.size, fx, fy, false) {
            let v = self.get(face, i / self.size, i % self.size);
            for k in 0..3 {
                out[k] += w as f32 * v[k];
            }
        }
        out
    }

    /// The next mip level: each texel is the solid-angle-weighted mean of its 2×2 children, i.e.
    /// the exact mean radiance over its footprint, so ∫ L dω is preserved.
    pub fn downsample(&self) -> Result<CubeMap, CubeError> {
        if self.size % 2 == 1 {
            return Err(CubeError::Odd(self.size));
        }
        let child_omega = texel_solid_angles(self.size)?;
        let half = self.size / 2;
        let mut out = CubeMap::new(half)?;
        for face in FACES {
            for r in 0..half {
                for c in 0..half {
                    let (mut sum, mut omega) = ([0.0f64; 3], 0.0);
                    for (rr, cc) in [(2 * r, 2 * c), (2 * r, 2 * c + 1), (2 * r + 1, 2 * c), (2 * r + 1, 2 * c + 1)] {
                        let w = child_omega[rr * self.size + cc];
                        let v = self.get(face, rr, cc);
                        for ch in 0..3 {
                            sum[ch] += w * v[ch] as f64;
                        }
                        omega += w;
                    }
                    out.set(face, r, c, [(sum[0] / omega) as f32, (sum[1] / omega) as f32, (sum[2] / omega) as f32]);
                }
            }
        }
        Ok(out)
    }
}

/// A chain of cube levels, largest first, each half the size of the previous.
#[derive(Clone, Debug, PartialEq)]
pub struct CubeMipChain {
    levels: Vec<CubeMap>,
}

impl CubeMipChain {
    /// Wraps levels, checking that each halves the previous.
    pub fn new(levels: Vec<CubeMap>) -> Result<Self, CubeError> {
        let first = levels.first().ok_or(CubeError::Empty)?.size;
        for (i, level) in levels.iter().enumerate() {
            let expected = first >> i;
            if level.size != expected || expected == 0 {
                return Err(CubeError::Chain { level: i, size: level.size, expected: expected.max(1) });
            }
        }
        Ok(CubeMipChain { levels })
    }

    /// The box pyramid of `base`, halving until the face is `min_size` (or odd).
    pub fn pyramid(base: CubeMap, min_size: usize) -> Result<Self, CubeError> {
        let mut levels = vec![base];
        loop {
            let last = &levels[levels.len() - 1];
            if last.size / 2 < min_size.max(1) || last.size % 2 == 1 {
                break;
            }
            let next = last.downsample()?;
            levels.push(next);
        }
        Ok(CubeMipChain { levels })
    }

    /// The levels, largest first.
    pub fn levels(&self) -> &[CubeMap] {
        &self.levels
    }

    /// The largest level.
    pub fn base(&self) -> &CubeMap {
        &self.levels[0]
    }

    /// Number of levels.
    pub fn len(&self) -> usize {
        self.levels.len()
    }

    /// Always false: a chain has at least one level.
    pub fn is_empty(&self) -> bool {
        self.levels.is_empty()
    }

    /// The chain as texture data for the KTX2 and DDS writers (`crate::io::texture`): a cube,
    /// three channels, largest level first.
    pub fn as_texture(&self) -> Texture<'_> {
        Texture {
            shape: TextureShape::Cube { size: self.base().size },
            channels: 3,
            levels: self.levels.iter().map(|l| l.texels()).collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::envmap::Layout;
    use std::f64::consts::PI;

    /// The Vulkan face-selection table, transcribed from the specification independently of
    /// [`face_coordinates`]: (face index, s_c, t_c, m_a) for a direction whose major axis is known.
    fn vulkan_select(r: DVec3) -> (usize, f64, f64) {
        let a = r.abs();
        let (face, sc, tc, ma) = if a.x >= a.y && a.x >= a.z {
            if r.x > 0.0 {
                (0, -r.z, -r.y, a.x)
            } else {
                (1, r.z, -r.y, a.x)
            }
        } else if a.y >= a.z {
            if r.y > 0.0 {
                (2, r.x, r.z, a.y)
            } else {
                (3, r.x, -r.z, a.y)
            }
        } else if r.z > 0.0 {
            (4, r.x, -r.y, a.z)
        } else {
            (5, -r.x, -r.y, a.z)
        };
        (face, 0.5 * (sc / ma + 1.0), 0.5 * (tc / ma + 1.0))
    }

    #[test]
    fn texel_centres_are_where_the_vulkan_sampler_reads_them() {
        let n = 8;
        for face in FACES {
            for row in 0..n {
                for col in 0..n {
                    let d = texel_direction(face, n, row, col);
                    let (f, u, v) = vulkan_select(d);
                    assert_eq!(f, face.index());
                    assert!((u * n as f64 - (col as f64 + 0.5)).abs() < 1e-12);
                    assert!((v * n as f64 - (row as f64 + 0.5)).abs() < 1e-12);
                    assert_eq!(texel_of(d, n), (face, row, col));
                }
            }
        }
    }

    #[test]
    fn direction_round_trips() {
        let mut x = 0.123f64;
        for _ in 0..2000 {
            // A deterministic spread of directions (golden-ratio sequence on the sphere).
            x = (x + 0.618_033_988_749_895) % 1.0;
            let z = 2.0 * x - 1.0;
            let phi = 2.0 * PI * ((x * 7919.0) % 1.0);
            let d = DVec3::new((1.0 - z * z).sqrt() * phi.cos(), (1.0 - z * z).sqrt() * phi.sin(), z);
            let (face, s, t) = face_coordinates(d);
            assert!(s.abs() <= 1.0 && t.abs() <= 1.0);
            assert!((face_direction(face, s, t).normalize() - d).length() < 1e-12, "{d}");
            let (vf, u, v) = vulkan_select(d);
            assert_eq!(vf, face.index());
            assert!((u - 0.5 * (s + 1.0)).abs() < 1e-12 && (v - 0.5 * (t + 1.0)).abs() < 1e-12);
        }
    }

    #[test]
    fn solid_angles_sum_to_the_sphere_and_match_the_area_element() {
        for n in [1, 2, 7, 64] {
            let omega = texel_solid_angles(n).unwrap();
            let total: f64 = 6.0 * omega.iter().sum::<f64>();
            assert!((total - 4.0 * PI).abs() < 1e-11, "n={n}: {total}");
        }
        // Independent check: the solid angle of a small texel is ≈ its face area over
        // (1 + s² + t²)^{3/2} (the plane at distance 1 seen from the centre).
        let n = 512;
        let omega = texel_solid_angles(n).unwrap();
        for (row, col) in [(0, 0), (100, 300), (255, 256), (511, 17)] {
            let (s, t) = (texel_coordinate(n, col), texel_coordinate(n, row));
            let approx = (2.0 / n as f64).powi(2) / (1.0 + s * s + t * t).powf(1.5);
            assert!((omega[row * n + col] / approx - 1.0).abs() < 1e-4, "({row},{col})");
        }
    }

    #[test]
    fn adjacent_faces_share_their_edges() {
        // Across every edge, the two edge texels' centres are one texel apart, and the edge
        // point between them maps to both faces' boundary (s or t = ±1).
        let n = 16;
        let spacing = texel_direction(Face::PosZ, n, n / 2, n / 2).angle_between(texel_direction(
            Face::PosZ,
            n,
            n / 2,
            n / 2 + 1,
        ));
        for face in FACES {
            for k in 0..n {
                for (row, col) in [(0, k), (n - 1, k), (k, 0), (k, n - 1)] {
                    let d = texel_direction(face, n, row, col);
                    // Step half a texel outwards across the edge: the point lands on the
                    // neighbouring face, whose nearest texel is the matching edge texel.
                    let (s, t) = (texel_coordinate(n, col), texel_coordinate(n, row));
                    let h = 1.0 / n as f64;
                    let (se, te) = if row == 0 {
                        (s, -1.0 - h)
                    } else if row == n - 1 {
                        (s, 1.0 + h)
                    } else if col == 0 {
                        (-1.0 - h, t)
                    } else {
                        (1.0 + h, t)
                    };
                    let beyond = face_direction(face, se, te).normalize();
                    let (nf, nr, nc) = texel_of(beyond, n);
                    assert_ne!(nf, face);
                    let neighbour = texel_direction(nf, n, nr, nc);
                    assert!(d.angle_between(neighbour) < 1.01 * spacing, "{face:?} ({row},{col}) → {nf:?} ({nr},{nc})");
                }
            }
        }
    }

    #[test]
    fn frame_is_a_proper_rotation_taking_z_up_to_y_up() {
        let m = WORLD_FROM_PRTKIT;
        assert!((m.determinant() - 1.0).abs() < 1e-15);
        assert!((m * m.transpose() - DMat3::IDENTITY).to_cols_array().iter().all(|v| v.abs() < 1e-15));
        assert_eq!(m * DVec3::Z, DVec3::Y);
        assert_eq!(m * DVec3::X, DVec3::X);
        assert_eq!(PRTKIT_FROM_WORLD, m.transpose());
        // Right-handedness is kept: x × y = z in both frames.
        assert!(((m * DVec3::X).cross(m * DVec3::Y) - m * DVec3::Z).length() < 1e-15);
    }

    #[test]
    fn a_bright_texel_at_prtkit_plus_x_lands_on_face_plus_x() {
        // A lat-long map (prtkit's frame), black but for the four texels around prtkit's +X
        // (θ = π/2, φ = 0), resampled into the glTF-frame cube: the brightest texels are the
        // centre of face +X. Likewise the zenith (+Z) lands on +Y and prtkit's +Y on −Z.
        let (w, h) = (64, 32);
        for (target, face) in [(DVec3::X, Face::PosX), (DVec3::Z, Face::PosY), (DVec3::Y, Face::NegZ)] {
            let img = RgbImage::from_fn(w, h, |x, y| {
                let d = crate::sphere::LatLong::new(w, h).texel_direction(x, y);
                if d.dot(target) > 0.995 {
                    [100.0; 3]
                } else {
                    [0.0; 3]
                }
            });
            let env = EnvMap::new(Layout::LatLong, img).unwrap();
            let cube = CubeMap::resample(&env, 8, 4, PRTKIT_FROM_WORLD).unwrap();
            let mut best = (0.0f32, Face::PosX, 0, 0);
            for f in FACES {
                for r in 0..8 {
                    for c in 0..8 {
                        let v = cube.get(f, r, c)[0];
                        if v > best.0 {
                            best = (v, f, r, c);
                        }
                    }
                }
            }
            assert_eq!(best.1, face, "{target}: {best:?}");
            assert!((3..=4).contains(&best.2) && (3..=4).contains(&best.3), "{target}: {best:?}");
            assert_eq!(texel_of(WORLD_FROM_PRTKIT * target, 8).0, face);
        }
    }

    #[test]
    fn pyramid_preserves_the_integral_and_halves() {
        let base = CubeMap::from_fn(32, |d| [(d.x * 3.0).exp() as f32, (d.y + 1.0) as f32, 1.0]).unwrap();
        let integral = |c: &CubeMap| -> [f64; 3] {
            let omega = texel_solid_angles(c.size()).unwrap();
            let mut s = [0.0; 3];
            for face in FACES {
                for i in 0..c.size() * c.size() {
                    let v = c.get(face, i / c.size(), i % c.size());
                    for ch in 0..3 {
                        s[ch] += omega[i] * v[ch] as f64;
                    }
                }
            }
            s
        };
        let want = integral(&base);
        let chain = CubeMipChain::pyramid(base, 4).unwrap();
        assert_eq!(chain.levels().iter().map(|l| l.size()).collect::<Vec<_>>(), vec![32, 16, 8, 4]);
        for level in chain.levels() {
            let got = integral(level);
            for ch in 0..3 {
                assert!((got[ch] / want[ch] - 1.0).abs() < 1e-6, "{}: {got:?} vs {want:?}", level.size());
            }
        }
        // The constant channel stays exactly constant.
        assert!(chain.levels()[3].texels().chunks(3).all(|p| (p[2] - 1.0).abs() < 1e-6));
    }

    #[test]
    fn chains_write_to_ktx2_with_faces_in_place() {
        // A cube bright only around world +X, written as a 2-level KTX2 and read back with the
        // `ktx2` crate: the brightest texels of level 0 are in the first face block, +X.
        let cube = CubeMap::from_fn(4, |d| if d.x > 0.9 { [5.0; 3] } else { [0.0; 3] }).unwrap();
        let chain = CubeMipChain::pyramid(cube, 2).unwrap();
        let bytes =
            crate::io::ktx2::encode(&chain.as_texture(), crate::io::gpu_format::TexelFormat::Rgba32Float).unwrap();
        let reader = ktx2::Reader::new(&bytes).unwrap();
        let level0 = reader.levels().next().unwrap().data;
        let face_bytes = 4 * 4 * 16;
        let red = |i: usize| f32::from_le_bytes(level0[16 * i..16 * i + 4].try_into().unwrap());
        let brightest = (0..6 * 16).max_by(|&a, &b| red(a).total_cmp(&red(b))).unwrap();
        assert_eq!(brightest * 16 / face_bytes, Face::PosX.index());
        assert_eq!(reader.header().level_count, 2);
    }

    #[test]
    fn bad_sizes_are_errors() {
        assert_eq!(CubeMap::new(0), Err(CubeError::Size(0)));
        assert_eq!(CubeMap::new(3).unwrap().downsample(), Err(CubeError::Odd(3)));
        let chain = CubeMipChain::new(vec![CubeMap::new(8).unwrap(), CubeMap::new(2).unwrap()]);
        assert_eq!(chain, Err(CubeError::Chain { level: 1, size: 2, expected: 4 }));
        assert_eq!(CubeMipChain::new(vec![]), Err(CubeError::Empty));
    }
}
