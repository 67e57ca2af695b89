//! Environment-map parameterizations: per-texel direction and exact solid angle, lookup by
//! direction, layout detection and resampling. Mappings to the +Z-up frame are documented in
//! `docs/envmap-layouts.md`.

pub mod bright;
mod cube;
mod layout;
mod load;
mod orient;
mod probe;
pub mod resample;
pub mod stage;
pub mod zonal;

pub use cube::{select_face, Face, FACES};
pub use layout::Layout;
pub use load::{LoadError, LoadOptions, Loaded, NegativePolicy, PixelFault};
pub use orient::Orientation;
pub use probe::WORLD_FROM_PROBE;
pub use resample::resample;

use crate::io::RgbImage;
use crate::sphere::latlong::{bilinear_taps, LatLong, TapLanes, LANES};
use glam::DVec3;

/// Errors about environment-map geometry.
#[derive(Debug, thiserror::Error)]
pub enum EnvMapError {
    /// The image size does not fit the requested or detected layout.
    #[error("a {width}x{height} image cannot be a {layout} map: {reason}")]
    BadSize {
        /// Layout name.
        layout: &'static str,
        /// Width.
        width: usize,
        /// Height.
        height: usize,
        /// Why.
        reason: String,
    },
    /// The aspect ratio matches no layout.
    #[error("cannot tell the layout of a {width}x{height} image from its aspect ratio (2:1 lat-long, 1:1 angular probe, 4:3 or 3:4 cube cross)")]
    Undetectable {
        /// Width.
        width: usize,
        /// Height.
        height: usize,
    },
}

/// An environment map: one image (or six cube faces) and its layout.
#[derive(Clone, Debug)]
pub struct EnvMap {
    layout: Layout,
    /// One image, or six faces in the order +X, −X, +Y, −Y, +Z, −Z for [`Layout::Faces`].
    images: Vec<RgbImage>,
    /// How the file was turned on reading (`orient`).
    orientation: Orientation,
}

/// One texel: its direction (unit, +Z up), its exact solid angle and its radiance.
#[derive(Clone, Copy, Debug)]
pub struct Texel {
    /// Unit direction of the texel centre.
    pub dir: DVec3,
    /// Solid angle covered by the texel (steradians).
    pub solid_angle: f64,
    /// Linear RGB radiance.
    pub rgb: [f32; 3],
}

impl EnvMap {
    /// Wraps one image in a layout (not [`Layout::Faces`]), checking its size.
    pub fn new(layout: Layout, image: RgbImage) -> Result<Self, EnvMapError> {
        layout.check_size(image.width, image.height)?;
        if layout == Layout::Faces {
            return Err(EnvMapError::BadSize {
                layout: layout.name(),
                width: image.width,
                height: image.height,
                reason: "six face images are needed".into(),
            });
        }
        Ok(EnvMap { layout, images: vec![image], orientation: Orientation::AsStored })
    }

    /// Wraps one image, detecting the layout from its aspect ratio.
    pub fn detect(image: RgbImage) -> Result<Self, EnvMapError> {
        let layout = Layout::detect(image.width, image.height)?;
        EnvMap::new(layout, image)
    }

    /// Six square faces of equal size in the order +X, −X, +Y, −Y, +Z, −Z.
    pub fn from_faces(faces: Vec<RgbImage>) -> Result<Self, EnvMapError> {
        let n = faces.first().map(|f| f.width).unwrap_or(0);
        if faces.len() != 6 || faces.iter().any(|f| f.width != n || f.height != n) || n == 0 {
            let (w, h) = faces.first().map(|f| (f.width, f.height)).unwrap_or((0, 0));
            return Err(EnvMapError::BadSize {
                layout: "cube faces",
                width: w,
                height: h,
                reason: "six square faces of one size are needed".into(),
            });
        }
        Ok(EnvMap { layout: Layout::Faces, images: faces, orientation: Orientation::AsStored })
    }

    /// A lat-long map.
    pub fn latlong(image: RgbImage) -> Result<Self, EnvMapError> {
        EnvMap::new(Layout::LatLong, image)
    }

    /// The layout.
    pub fn layout(&self) -> Layout {
        self.layout
    }

    /// The image (the first face for [`Layout::Faces`]).
    pub fn image(&self) -> &RgbImage {
        &self.images[0]
    }

    /// All images (six for faces, one otherwise).
    pub fn images(&self) -> &[RgbImage] {
        &self.images
    }

    /// Mutable access to the pixels (same geometry).
    pub fn images_mut(&mut self) -> &mut [RgbImage] {
        &mut self.images
    }

    /// Number of texels with non-zero solid angle, roughly (all pixels of all images).
    pub fn texel_count(&self) -> usize {
        self.images.iter().map(|i| i.width * i.height).sum()
    }

    /// The highest SH order this map can resolve: √(N/2) for N texels (a lat-long W×H map
    /// resolves l < H; (F+1)² coefficients need about as many samples, times the 2 of Nyquist).
    pub fn max_order(&self) -> usize {
        ((self.texel_count() as f64 / 2.0).sqrt().floor() as usize).max(1)
    }

    /// Direction and solid angle of pixel (x, y) of image `face` (0 for single-image layouts);
    /// `None` outside the mapped area (the corners of an angular probe, the empty cells of a
    /// cross).
    pub fn texel_geometry(&self, face: usize, x: usize, y: usize) -> Option<(DVec3, f64)> {
        let img = &self.images[face];
        let (w, h) = (img.width, img.height);
        match self.layout {
            Layout::LatLong => {
                let grid = LatLong::new(w, h);
                Some((grid.texel_direction(x, y), grid.row_solid_angle(y)))
            }
            Layout::Angular => probe::texel(w, x, y),
            Layout::CrossHorizontal | Layout::CrossVertical => {
                let n = self.layout.face_size(w, h);
                let (face, fx, fy) = cube::cross_to_face(self.layout, n, x, y)?;
                Some(cube::texel(face, n, fx, fy))
            }
            Layout::Faces => Some(cube::texel(FACES[face], w, x, y)),
        }
    }

    /// The solid angle of pixel (x, y) of image `face`, as [`EnvMap::texel_geometry`] gives it
    /// (a lat-long row's without computing the direction).
    pub fn texel_solid_angle(&self, face: usize, x: usize, y: usize) -> Option<f64> {
        match self.layout {
            Layout::LatLong => {
                let img = &self.images[face];
                Some(LatLong::new(img.width, img.height).row_solid_angle(y))
            }
            _ => self.texel_geometry(face, x, y).map(|(_, omega)| omega),
        }
    }

    /// Calls `f` with the column, value and solid angle of every mapped texel of row `y` of image
    /// `face`, in the order of [`EnvMap::for_each_texel`], without the directions (a lat-long
    /// row's solid angle once): rows as units of parallel work.
    pub fn for_each_value_in_row(&self, face: usize, y: usize, mut f: impl FnMut(usize, [f32; 3], f64)) {
        let row_omega = (self.layout == Layout::LatLong).then(|| self.texel_solid_angle(face, 0, y)).flatten();
        for (x, &rgb) in self.images[face].row(y).iter().enumerate() {
            if let Some(omega) = row_omega.or_else(|| self.texel_solid_angle(face, x, y)) {
                f(x, rgb, omega);
            }
        }
    }

    /// Calls `f` for every mapped texel, image by image, row by row.
    pub fn for_each_texel(&self, mut f: impl FnMut(Texel)) {
        if self.layout == Layout::LatLong {
            // The same directions as `texel_geometry`, from sin/cos tabulated per row and column.
            let img = &self.images[0];
            let grid = LatLong::new(img.width, img.height);
            let columns: Vec<(f64, f64)> = (0..img.width).map(|x| grid.column_phi(x).sin_cos()).collect();
            for y in 0..img.height {
                let (st, ct) = grid.row_theta(y).sin_cos();
                let solid_angle = grid.row_solid_angle(y);
                for (x, &(sp, cp)) in columns.iter().enumerate() {
                    f(Texel { dir: DVec3::new(st * cp, st * sp, ct), solid_angle, rgb: img.get(x, y) });
                }
            }
            return;
        }
        for (face, img) in self.images.iter().enumerate() {
            for y in 0..img.height {
                for x in 0..img.width {
                    if let Some((dir, solid_angle)) = self.texel_geometry(face, x, y) {
                        f(Texel { dir, solid_angle, rgb: img.get(x, y) });
                    }
                }
            }
        }
    }

    /// Rows of texels as independent units of work: (image index, row).
    pub fn rows(&self) -> Vec<(usize, usize)> {
        self.images.iter().enumerate().flat_map(|(f, img)| (0..img.height).map(move |y| (f, y))).collect()
    }

    /// [`EnvMap::lookup`] of many directions (need not be normalized) into `out`, one per
    /// direction: for lat-long maps in f32 SIMD lanes (positions within 0.002 of a texel of
    /// `lookup`'s), otherwise one `lookup` each.
    pub fn lookup_many(&self, dirs: &[[f32; 3]], out: &mut [[f32; 3]]) {
        assert_eq!(dirs.len(), out.len(), "one output per direction");
        match self.layout {
            Layout::LatLong => latlong_lookups(&self.images[0], dirs, out),
            _ => {
                for (d, o) in dirs.iter().zip(out) {
                    *o = self.lookup(DVec3::new(d[0] as f64, d[1] as f64, d[2] as f64));
                }
            }
        }
    }

    /// Bilinearly filtered radiance in direction `dir` (need not be normalized).
    pub fn lookup(&self, dir: DVec3) -> [f32; 3] {
        match self.layout {
            Layout::LatLong => {
                // `position` normalizes.
                let img = &self.images[0];
                let (px, py) = LatLong::new(img.width, img.height).position(dir);
                bilinear(img, px - 0.5, py - 0.5, true)
            }
            Layout::Angular => {
                let img = &self.images[0];
                let (fx, fy) = probe::pixel_of(img.width, dir.normalize());
                bilinear(img, fx, fy, false)
            }
            Layout::Faces | Layout::CrossHorizontal | Layout::CrossVertical => {
                let (face, s, t) = cube::face_coords(dir.normalize());
                let n = match self.layout {
                    Layout::Faces => self.images[0].width,
                    _ => self.layout.face_size(self.images[0].width, self.images[0].height),
                };
                // Texel-centre coordinates within the face, clamped to the face (no seams
                // filtering across faces; adequate for resampling with supersampling).
                let fx = ((s + 1.0) * 0.5 * n as f64 - 0.5).clamp(0.0, n as f64 - 1.0);
                let fy = ((t + 1.0) * 0.5 * n as f64 - 0.5).clamp(0.0, n as f64 - 1.0);
                match self.layout {
                    Layout::Faces => bilinear(&self.images[face.index()], fx, fy, false),
                    _ => {
                        let sample = |x: usize, y: usize| {
                            let (cx, cy) = cube::face_to_cross(self.layout, n, face, x, y);
                            self.images[0].get(cx, cy)
                        };
                        bilinear_with(n, n, fx, fy, false, sample)
                    }
                }
            }
        }
    }
}

/// [`EnvMap::lookup`] of every direction of a lat-long map, `LANES` at a time: the taps in f32
/// lanes ([`LatLong::taps_lanes`]), then the four texels of each read and weighed. Compiled for
/// baseline x86-64 and, through `pulp::Arch::dispatch`, once more with AVX2 (8 f32 lanes),
/// chosen at run time as in `normals::onv`: autovectorized safe Rust either way.
fn latlong_lookups(img: &RgbImage, dirs: &[[f32; 3]], out: &mut [[f32; 3]]) {
    struct Op<'a>(&'a RgbImage, &'a [[f32; 3]], &'a mut [[f32; 3]]);
    impl pulp::WithSimd for Op<'_> {
        type Output = ();
        #[inline(always)]
        fn with_simd<S: pulp::Simd>(self, _: S) {
            let Op(img, dirs, out) = self;
            let grid = LatLong::new(img.width, img.height);
            let (mut x, mut y, mut z) = ([1.0f32; LANES], [0.0f32; LANES], [0.0f32; LANES]);
            let mut taps = TapLanes::default();
            for (dirs, out) in dirs.chunks(LANES).zip(out.chunks_mut(LANES)) {
                for (i, d) in dirs.iter().enumerate() {
                    (x[i], y[i], z[i]) = (d[0], d[1], d[2]);
                }
                grid.taps_lanes(&x, &y, &z, &mut taps);
                for (i, o) in out.iter_mut().enumerate() {
                    let (x0, x1) = (taps.x0[i] as usize, taps.x1[i] as usize);
                    let (row0, row1) = (taps.y0[i] as usize * img.width, taps.y1[i] as usize * img.width);
                    let (tx, ty) = (taps.tx[i], taps.ty[i]);
                    let p = &img.pixels;
                    let (a, b, c, d) = (p[row0 + x0], p[row0 + x1], p[row1 + x0], p[row1 + x1]);
                    for k in 0..3 {
                        let top = a[k] + tx * (b[k] - a[k]);
                        let bottom = c[k] + tx * (d[k] - c[k]);
                        o[k] = top + ty * (bottom - top);
                    }
                }
            }
        }
    }
    pulp::Arch::new().dispatch(Op(img, dirs, out))
}

fn bilinear(img: &RgbImage, fx: f64, fy: f64, wrap_x: bool) -> [f32; 3] {
    bilinear_with(img.width, img.height, fx, fy, wrap_x, |x, y| img.get(x, y))
}

fn bilinear_with(
    width: usize,
    height: usize,
    fx: f64,
    fy: f64,
    wrap_x: bool,
    sample: impl Fn(usize, usize) -> [f32; 3],
) -> [f32; 3] {
    let mut out = [0.0f32; 3];
    for (i, w) in bilinear_taps(width, height, fx, fy, wrap_x) {
        let v = sample(i % width, i / width);
        for k in 0..3 {
            out[k] += w as f32 * v[k];
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn latlong_texels_come_in_order_with_the_geometry_of_texel_geometry() {
        // for_each_texel's lat-long path tabulates sin/cos per row and column; the directions,
        // solid angles and values must be texel_geometry's, bit for bit, in row-major order.
        let map = EnvMap::latlong(RgbImage::from_fn(12, 6, |x, y| [x as f32, y as f32, 1.0])).unwrap();
        let mut k = 0;
        map.for_each_texel(|t| {
            let (x, y) = (k % 12, k / 12);
            assert_eq!(Some((t.dir, t.solid_angle)), map.texel_geometry(0, x, y), "texel ({x}, {y})");
            assert_eq!(t.rgb, [x as f32, y as f32, 1.0]);
            k += 1;
        });
        assert_eq!(k, 72);
    }

    fn total_solid_angle(map: &EnvMap) -> f64 {
        let mut s = 0.0;
        map.for_each_texel(|t| s += t.solid_angle);
        s
    }

    #[test]
    fn solid_angles_sum_to_the_sphere() {
        let ll = EnvMap::latlong(RgbImage::new(64, 32)).unwrap();
        assert!((total_solid_angle(&ll) - 4.0 * PI).abs() < 1e-12);
        let faces = EnvMap::from_faces((0..6).map(|_| RgbImage::new(16, 16)).collect()).unwrap();
        assert!((total_solid_angle(&faces) - 4.0 * PI).abs() < 1e-12);
        let cross = EnvMap::new(Layout::CrossHorizontal, RgbImage::new(64, 48)).unwrap();
        assert!((total_solid_angle(&cross) - 4.0 * PI).abs() < 1e-12);
        let vcross = EnvMap::new(Layout::CrossVertical, RgbImage::new(48, 64)).unwrap();
        assert!((total_solid_angle(&vcross) - 4.0 * PI).abs() < 1e-12);
        let probe = EnvMap::new(Layout::Angular, RgbImage::new(256, 256)).unwrap();
        assert!((total_solid_angle(&probe) - 4.0 * PI).abs() < 1e-4, "{}", total_solid_angle(&probe));
    }

    #[test]
    fn lookup_inverts_texel_directions() {
        // Each texel's centre direction must look up that texel's own value, in every layout.
        let layouts = [
            EnvMap::latlong(RgbImage::from_fn(32, 16, |x, y| [x as f32, y as f32, 0.0])).unwrap(),
            EnvMap::new(Layout::Angular, RgbImage::from_fn(32, 32, |x, y| [x as f32, y as f32, 0.0])).unwrap(),
            EnvMap::new(Layout::CrossHorizontal, RgbImage::from_fn(32, 24, |x, y| [x as f32, y as f32, 0.0])).unwrap(),
            EnvMap::new(Layout::CrossVertical, RgbImage::from_fn(24, 32, |x, y| [x as f32, y as f32, 0.0])).unwrap(),
            EnvMap::from_faces(
                (0..6).map(|f| RgbImage::from_fn(8, 8, |x, y| [x as f32, y as f32, f as f32])).collect(),
            )
            .unwrap(),
        ];
        for map in &layouts {
            for (face, img) in map.images().iter().enumerate() {
                for y in 0..img.height {
                    for x in 0..img.width {
                        if let Some((dir, _)) = map.texel_geometry(face, x, y) {
                            let got = map.lookup(dir);
                            let want = img.get(x, y);
                            for k in 0..3 {
                                assert!(
                                    (got[k] - want[k]).abs() < 1e-3,
                                    "{:?} ({x},{y}): {got:?} vs {want:?}",
                                    map.layout()
                                );
                            }
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn lookup_many_is_lookup() {
        // On a 64 × 32 map the lanes' positions are within ~10⁻⁵ of a texel of `lookup`'s
        // (atan2_f32's 3·10⁻⁷ rad is 3·10⁻⁶ of a texel; f32 holds positions below 64 to 4·10⁻⁶),
        // and values in [0, 1] change by at most 1 per texel: within 10⁻⁴. Other layouts go
        // through `lookup` itself, so exactly. 1001 directions: no multiple of the lanes.
        let mut rng = crate::rng::SplitMix64::new(11);
        let pixels = (0..64 * 32).map(|_| [rng.next_f64() as f32, rng.next_f64() as f32, 0.5]).collect();
        let img = RgbImage { width: 64, height: 32, pixels };
        let cross = RgbImage::from_fn(32, 24, |x, y| [x as f32, y as f32, 0.0]);
        for (map, tolerance) in
            [(EnvMap::latlong(img).unwrap(), 1e-4), (EnvMap::new(Layout::CrossHorizontal, cross).unwrap(), 0.0)]
        {
            let dirs: Vec<[f32; 3]> = (0..1001)
                .map(|_| {
                    let d = rng.direction();
                    [d.x as f32, d.y as f32, d.z as f32]
                })
                .collect();
            let mut got = vec![[f32::NAN; 3]; dirs.len()];
            map.lookup_many(&dirs, &mut got);
            for (d, got) in dirs.iter().zip(&got) {
                let want = map.lookup(DVec3::new(d[0] as f64, d[1] as f64, d[2] as f64));
                for k in 0..3 {
                    assert!((got[k] - want[k]).abs() <= tolerance, "{:?} {d:?}: {got:?} vs {want:?}", map.layout());
                }
            }
        }
    }
}
