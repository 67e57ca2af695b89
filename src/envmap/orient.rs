//! How a map's file is turned on reading, and a fingerprint of what was read.
//!
//! Files come stored upside down: pbrt's `grace_latlong.exr` measures θ from a +Z that is the
//! cathedral's floor, and a PFM written by a tool that forgot its bottom-up row order is the
//! vertical mirror of its source. [`Orientation::FlipVertical`] undoes that on reading, for every
//! layout, so every stage sees the sky on +Z (`docs/envmap-layouts.md`, "Orientation").
//!
//! The flip is the mirror z → −z, an exact permutation of texels in every layout prtkit reads: a
//! lat-long map's rows in reverse (θ → π − θ), an angular probe's rows in reverse (its image up
//! is +Z, `probe::WORLD_FROM_PROBE`), and for cube maps the mirror maps each texel centre onto
//! another face's texel centre (the cube is symmetric under it). No value is interpolated.

use super::{cube, EnvMap, Layout, FACES};
use crate::io::RgbImage;
use glam::DVec3;

/// How a map is turned on reading.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Orientation {
    /// As the file stores it.
    #[default]
    AsStored,
    /// Mirrored top to bottom: the radiance the file has along (x, y, −z) is read along
    /// (x, y, z).
    FlipVertical,
}

impl Orientation {
    /// The words documents record in `conventions.input_orientation`.
    pub fn describe(self) -> &'static str {
        match self {
            Orientation::AsStored => "as stored",
            Orientation::FlipVertical => "flipped vertically on reading (z -> -z: a lat-long map's rows reversed)",
        }
    }
}

impl EnvMap {
    /// How this map was turned on reading.
    pub fn orientation(&self) -> Orientation {
        self.orientation
    }

    /// The map turned as `orientation` says (from the file as stored).
    pub fn oriented(self, orientation: Orientation) -> EnvMap {
        match orientation {
            Orientation::AsStored => self,
            Orientation::FlipVertical => self.flipped_vertically(),
        }
    }

    /// The map mirrored z → −z: what it had along (x, y, −z) it has along (x, y, z). Flipping
    /// twice gives the map back, bit for bit.
    pub fn flipped_vertically(self) -> EnvMap {
        let orientation = match self.orientation {
            Orientation::AsStored => Orientation::FlipVertical,
            Orientation::FlipVertical => Orientation::AsStored,
        };
        let images = match self.layout {
            Layout::LatLong | Layout::Angular => self.images.iter().map(rows_reversed).collect(),
            Layout::Faces | Layout::CrossHorizontal | Layout::CrossVertical => self.cube_mirrored_in_z(),
        };
        EnvMap { layout: self.layout, images, orientation }
    }

    /// Cube layouts: each texel takes the value of the texel its mirrored centre lands on.
    fn cube_mirrored_in_z(&self) -> Vec<RgbImage> {
        let (w, h) = (self.images[0].width, self.images[0].height);
        let n = match self.layout {
            Layout::Faces => w,
            _ => self.layout.face_size(w, h),
        };
        // The texel of `face` whose centre is nearest to face coordinates (s, t): exact here,
        // since mirrored centres fall on centres, half a texel from any edge.
        let index = |c: f64| (((c + 1.0) * 0.5 * n as f64).floor() as usize).min(n - 1);
        let source = |dir: DVec3| {
            let (face, s, t) = cube::face_coords(DVec3::new(dir.x, dir.y, -dir.z));
            (face, index(s), index(t))
        };
        match self.layout {
            Layout::Faces => FACES
                .iter()
                .map(|&face| {
                    RgbImage::from_fn(n, n, |x, y| {
                        let (from, sx, sy) = source(cube::texel(face, n, x, y).0);
                        self.images[from.index()].get(sx, sy)
                    })
                })
                .collect(),
            _ => vec![RgbImage::from_fn(w, h, |x, y| match cube::cross_to_face(self.layout, n, x, y) {
                Some((face, fx, fy)) => {
                    let (from, sx, sy) = source(cube::texel(face, n, fx, fy).0);
                    let (cx, cy) = cube::face_to_cross(self.layout, n, from, sx, sy);
                    self.images[0].get(cx, cy)
                }
                None => self.images[0].get(x, y),
            })],
        }
    }

    /// A fingerprint of the map as read (layout, sizes and every texel's bits, after the
    /// orientation): `fnv1a64:` and 16 hex digits. Bakes record it so that a reader given
    /// another map, or the same map turned otherwise, can tell (FNV-1a over 32-bit words: not
    /// cryptographic; it tells maps apart, it does not authenticate them).
    pub fn content_hash(&self) -> String {
        const OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
        const PRIME: u64 = 0x0000_0100_0000_01b3;
        let mix = |h: u64, word: u32| (h ^ u64::from(word)).wrapping_mul(PRIME);
        let mut h = self.layout.name().bytes().fold(OFFSET, |h, b| mix(h, u32::from(b)));
        for image in &self.images {
            h = mix(mix(h, image.width as u32), image.height as u32);
            h = image.pixels.iter().flatten().fold(h, |h, v| mix(h, v.to_bits()));
        }
        format!("fnv1a64:{h:016x}")
    }
}

fn rows_reversed(image: &RgbImage) -> RgbImage {
    RgbImage::from_fn(image.width, image.height, |x, y| image.get(x, image.height - 1 - y))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A map whose value at each texel is its direction (x, y, z): the flip's definition can be
    /// read off every texel.
    fn directions(layout: Layout, w: usize, h: usize) -> EnvMap {
        let probe = if layout == Layout::Faces {
            EnvMap::from_faces(vec![RgbImage::new(w, w); 6]).unwrap()
        } else {
            EnvMap::new(layout, RgbImage::new(w, h)).unwrap()
        };
        let mut images = probe.images.clone();
        for (face, image) in images.iter_mut().enumerate() {
            for y in 0..image.height {
                for x in 0..image.width {
                    if let Some((d, _)) = probe.texel_geometry(face, x, y) {
                        image.set(x, y, [d.x as f32, d.y as f32, d.z as f32]);
                    }
                }
            }
        }
        EnvMap { images, ..probe }
    }

    #[test]
    fn every_layout_flips_z_exactly_and_twice_is_the_identity() {
        for (layout, w, h) in [
            (Layout::LatLong, 16, 8),
            (Layout::Angular, 12, 12),
            (Layout::Faces, 6, 6),
            (Layout::CrossHorizontal, 24, 18),
            (Layout::CrossVertical, 18, 24),
        ] {
            let map = directions(layout, w, h);
            let flipped = map.clone().flipped_vertically();
            assert_eq!(flipped.orientation(), Orientation::FlipVertical);
            for (face, image) in flipped.images.iter().enumerate() {
                for y in 0..image.height {
                    for x in 0..image.width {
                        let Some((d, _)) = flipped.texel_geometry(face, x, y) else { continue };
                        let v = image.get(x, y);
                        let want = [d.x as f32, d.y as f32, -d.z as f32];
                        for c in 0..3 {
                            assert!(
                                (v[c] - want[c]).abs() < 1e-5,
                                "{layout:?} face {face} ({x}, {y}): {v:?} vs {want:?}"
                            );
                        }
                    }
                }
            }
            let back = flipped.flipped_vertically();
            assert_eq!(back.orientation(), Orientation::AsStored);
            assert_eq!(back.images, map.images, "{layout:?}: flipping twice");
            assert_eq!(back.content_hash(), map.content_hash());
        }
    }

    #[test]
    fn the_hash_tells_maps_apart_and_ignores_nothing_that_was_read() {
        let map = directions(Layout::LatLong, 16, 8);
        let mut nudged = map.clone();
        let v = nudged.images[0].get(3, 2);
        nudged.images[0].set(3, 2, [f32::from_bits(v[0].to_bits() ^ 1), v[1], v[2]]);
        let flipped = map.clone().flipped_vertically();
        let hashes = [map.content_hash(), nudged.content_hash(), flipped.content_hash()];
        assert!(hashes[0] != hashes[1] && hashes[0] != hashes[2] && hashes[1] != hashes[2], "{hashes:?}");
        assert_eq!(map.content_hash(), map.clone().content_hash());
        assert!(hashes[0].starts_with("fnv1a64:") && hashes[0].len() == 8 + 16);
    }
}
