//! Resampling: between layouts ([`resample`]: every destination texel averages k×k bilinear
//! lookups of the source at sub-texel directions, a box filter over the texel's footprint), and
//! a lat-long map to a coarser lat-long grid exactly ([`box_latlong`]).

use super::{cube, probe, EnvMap, EnvMapError, Layout, FACES};
use crate::io::RgbImage;
use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::PI;

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
/// `supersample`² lookups per texel. The same layout at the same size is `src` itself: its
/// texels already are the map, and lookups about their centres would only blur them.
pub fn resample(
    src: &EnvMap,
    layout: Layout,
    width: usize,
    height: usize,
    supersample: usize,
) -> Result<EnvMap, EnvMapError> {
    layout.check_size(width, height)?;
    if src.layout == layout && src.images.iter().all(|i| (i.width, i.height) == (width, height)) {
        return Ok(src.clone());
    }
    let count = if layout == Layout::Faces { 6 } else { 1 };
    let blank: Vec<RgbImage> = (0..count).map(|_| RgbImage::new(width, height)).collect();
    let mut dst = EnvMap { layout, images: blank, orientation: src.orientation };
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

/// The overlaps of the cells of two partitions of one interval, given by their increasing
/// boundaries `a` (source) and `b` (target): (target cell, source cell, overlap length).
fn overlaps(a: &[f64], b: &[f64]) -> Vec<(usize, usize, f64)> {
    let mut out = Vec::with_capacity(a.len() + b.len());
    let (mut i, mut j) = (0, 0);
    while i + 1 < a.len() && j + 1 < b.len() {
        let lo = a[i].max(b[j]);
        let hi = a[i + 1].min(b[j + 1]);
        if hi > lo {
            out.push((j, i, hi - lo));
        }
        if a[i + 1] < b[j + 1] {
            i += 1;
        } else {
            j += 1;
        }
    }
    out
}

/// Resamples a lat-long image to a coarser W' × H' so that each texel is the exact mean radiance
/// over its footprint: a lat-long texel is a product of an interval in φ and one in z = cos θ,
/// in which the solid angle is dz dφ, so two texels overlap in the product of their intervals'
/// overlaps and the mean is separable (columns, then rows). ∫ L dω is kept.
pub fn box_latlong(img: &RgbImage, width: usize, height: usize) -> RgbImage {
    let (w, h) = (img.width, img.height);
    let phi = |n: usize| (0..=n).map(|k| k as f64 / n as f64).collect::<Vec<_>>();
    // z boundaries in increasing order: row 0 is the top, so these run from the bottom row up;
    // −cos(πk/n) increases with k, and row k spans [−cos(πk/n), −cos(π(k+1)/n)] of −z.
    let z = |n: usize| (0..=n).map(|k| -(PI * k as f64 / n as f64).cos()).collect::<Vec<_>>();
    let columns = overlaps(&phi(w), &phi(width));
    let (z_in, z_out) = (z(h), z(height));
    let rows = overlaps(&z_in, &z_out);
    // Each output row from its input rows, side by side: an input row's columns are filtered
    // once per output row it overlaps (at most two when shrinking).
    let mut sources = vec![Vec::new(); height];
    for &(y_out, y_in, len) in &rows {
        sources[y_out].push((y_in, len / (z_out[y_out + 1] - z_out[y_out])));
    }
    // Each row written once, in place (no page is read before it is written).
    let mut pixels = vec![[0.0f32; 3]; width * height];
    pixels.par_chunks_mut(width.max(1)).zip(&sources).for_each(|(row, sources)| {
        let (mut out, mut wide) = (vec![[0.0f64; 3]; width], vec![[0.0f64; 3]; width]);
        for &(y_in, share) in sources {
            let input = &img.pixels[y_in * w..(y_in + 1) * w];
            // An output column's overlaps are consecutive in `columns`: its sum is kept in
            // registers and stored once (a store per input texel made each add wait for the last).
            let mut overlaps = columns.iter().peekable();
            for (x_out, sum) in wide.iter_mut().enumerate() {
                let mut acc = [0.0f64; 3];
                while let Some(&(_, x_in, len)) = overlaps.next_if(|o| o.0 == x_out) {
                    let v = input[x_in];
                    for c in 0..3 {
                        acc[c] += v[c] as f64 * len * width as f64;
                    }
                }
                *sum = acc;
            }
            for (o, w) in out.iter_mut().zip(&wide) {
                for c in 0..3 {
                    o[c] += w[c] * share;
                }
            }
        }
        for (p, o) in row.iter_mut().zip(&out) {
            *p = o.map(|v| v as f32);
        }
    });
    RgbImage { width, height, pixels }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sphere::LatLong;

    /// The same layout at the same size keeps every texel bit for bit (a supersampled resample
    /// would average each texel with its neighbours); another size still resamples.
    #[test]
    fn resampling_into_the_same_grid_keeps_the_texels() {
        let img = RgbImage::from_fn(64, 32, |x, y| [(x * 7 % 5) as f32, (y % 3) as f32, (x ^ y) as f32 * 0.1]);
        let map = EnvMap::latlong(img.clone()).unwrap();
        let same = resample(&map, Layout::LatLong, 64, 32, 2).unwrap();
        assert_eq!(same.image().pixels, img.pixels);
        let cube = resample(&map, Layout::Faces, 16, 16, 2).unwrap();
        let again = resample(&cube, Layout::Faces, 16, 16, 2).unwrap();
        assert_eq!(again.images(), cube.images());
        let smaller = resample(&map, Layout::LatLong, 32, 16, 2).unwrap();
        assert_eq!((smaller.image().width, smaller.image().height), (32, 16));
    }

    #[test]
    fn box_resampling_keeps_the_integral_at_any_ratio() {
        let img = RgbImage::from_fn(64, 32, |x, y| [(x * y) as f32, 1.0, (x % 3) as f32]);
        let integral = |i: &RgbImage| -> [f64; 3] {
            let g = LatLong::new(i.width, i.height);
            let mut s = [0.0; 3];
            for y in 0..i.height {
                for x in 0..i.width {
                    for c in 0..3 {
                        s[c] += g.row_solid_angle(y) * i.get(x, y)[c] as f64;
                    }
                }
            }
            s
        };
        let a = integral(&img);
        for (w, h) in [(32, 16), (40, 20), (26, 13)] {
            let r = box_latlong(&img, w, h);
            let b = integral(&r);
            for c in 0..3 {
                assert!((a[c] / b[c] - 1.0).abs() < 1e-6, "{w}x{h}: {a:?} {b:?}");
            }
            // A constant channel stays exactly constant.
            assert!(r.pixels.iter().all(|p| (p[1] - 1.0).abs() < 1e-6));
        }
        // Halving is the 2 × 2 mean weighted by the rows' solid angles.
        let half = box_latlong(&img, 32, 16);
        let g = LatLong::new(64, 32);
        let (w0, w1) = (g.row_solid_angle(6), g.row_solid_angle(7));
        let want = (w0 * (img.get(10, 6)[0] + img.get(11, 6)[0]) as f64
            + w1 * (img.get(10, 7)[0] + img.get(11, 7)[0]) as f64)
            / (2.0 * (w0 + w1));
        assert!((half.get(5, 3)[0] as f64 - want).abs() < 1e-4 * want, "{} vs {want}", half.get(5, 3)[0]);
    }
}
