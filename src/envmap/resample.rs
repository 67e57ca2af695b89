//! Resampling between layouts: every destination texel averages k×k bilinear lookups of the
//! source at sub-texel directions (a box filter over the texel's footprint).

use super::{cube, probe, EnvMap, EnvMapError, Layout, FACES};
use crate::io::RgbImage;
use glam::DVec3;
use rayon::prelude::*;

impl EnvMap {
    /// Direction at continuous position (px, py) of image `face` (pixel x spans [x, x+1]), or
    /// `None` outside the mapped area.
    pub fn direction_at(&self, face: usize, px: f64, py: f64) -> Option<DVec3> {
        let img = &self.images[face];
        let (w, h) = (img.width, img.height);
        match self.layout {
            Layout::LatLong => Some(crate::sphere::LatLong::new(w, h).direction_at(px, py)),
            Layout::Angular => probe::direction_at(w, px, py),
            Layout::Faces => Some(cube::direction_at(FACES[face], w, px, py)),
            Layout::CrossHorizontal | Layout::CrossVertical => {
                let n = self.layout.face_size(w, h);
                let (x, y) = ((px.max(0.0) as usize).min(w - 1), (py.max(0.0) as usize).min(h - 1));
                let (f, _, _) = cube::cross_to_face(self.layout, n, x, y)?;
                let (cx0, _) = cube::face_to_cross(self.layout, n, f, 0, 0);
                let (cx1, _) = cube::face_to_cross(self.layout, n, f, n - 1, n - 1);
                let rotated = cx1 < cx0;
                let (mut fx, mut fy) = (px - (x / n * n) as f64, py - (y / n * n) as f64);
                if rotated {
                    fx = n as f64 - fx;
                    fy = n as f64 - fy;
                }
                Some(cube::direction_at(f, n, fx, fy))
            }
        }
    }
}

/// Resamples `src` into `layout` at `width`×`height` (per face for [`Layout::Faces`]), averaging
/// `supersample`² lookups per texel.
pub fn resample(
    src: &EnvMap,
    layout: Layout,
    width: usize,
    height: usize,
    supersample: usize,
) -> Result<EnvMap, EnvMapError> {
    layout.check_size(width, height)?;
    let count = if layout == Layout::Faces { 6 } else { 1 };
    let blank: Vec<RgbImage> = (0..count).map(|_| RgbImage::new(width, height)).collect();
    let mut dst = EnvMap { layout, images: blank };
    let k = supersample.max(1);
    let geometry = dst.clone();
    for (face, img) in dst.images.iter_mut().enumerate() {
        img.pixels.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
            for (x, px) in row.iter_mut().enumerate() {
                let mut sum = [0.0f64; 3];
                let mut hits = 0usize;
                for j in 0..k {
                    for i in 0..k {
                        let fx = x as f64 + (i as f64 + 0.5) / k as f64;
                        let fy = y as f64 + (j as f64 + 0.5) / k as f64;
                        if let Some(dir) = geometry.direction_at(face, fx, fy) {
                            let v = src.lookup(dir);
                            for c in 0..3 {
                                sum[c] += v[c] as f64;
                            }
                            hits += 1;
                        }
                    }
                }
                if hits > 0 {
                    *px = [(sum[0] / hits as f64) as f32, (sum[1] / hits as f64) as f32, (sum[2] / hits as f64) as f32];
                }
            }
        });
    }
    Ok(dst)
}
