//! Cube maps: six faces in the Direct3D/OpenGL orientation, and the two cross layouts.
//!
//! For face texel (row r, column c) of an n×n face, s = 2(c+0.5)/n − 1 and t = 2(r+0.5)/n − 1;
//! in the cube's own frame (y up) the texel looks along
//! +X (1, −t, −s), −X (−1, −t, s), +Y (s, 1, t), −Y (s, −1, −t), +Z (s, −t, 1), −Z (−s, −t, −1).
//! `WORLD_FROM_CUBE` takes that frame to prtkit's +Z-up frame (`docs/envmap-layouts.md`).

use super::Layout;
use glam::{DMat3, DVec3};

/// Cube frame → world: cube +Y (up) is world +Z; chosen so the DirectX SDK cubes of Debevec's
/// probes agree with pbrt's lat-long conversion (checked in the tests).
pub(crate) const WORLD_FROM_CUBE: DMat3 = DMat3::from_cols(
    DVec3::new(0.0, -1.0, 0.0), // cube x
    DVec3::new(0.0, 0.0, 1.0),  // cube y
    DVec3::new(-1.0, 0.0, 0.0), // cube z
);

/// A cube face.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Face {
    /// +X
    PosX,
    /// −X
    NegX,
    /// +Y
    PosY,
    /// −Y
    NegY,
    /// +Z
    PosZ,
    /// −Z
    NegZ,
}

/// Faces in file order.
pub const FACES: [Face; 6] = [Face::PosX, Face::NegX, Face::PosY, Face::NegY, Face::PosZ, Face::NegZ];

impl Face {
    /// Position in [`FACES`].
    pub fn index(self) -> usize {
        FACES.iter().position(|&f| f == self).unwrap_or(0)
    }

    /// Conventional short file name (`px`, `nx`, …).
    pub fn short_name(self) -> &'static str {
        ["px", "nx", "py", "ny", "pz", "nz"][self.index()]
    }

    /// Cube-frame direction (not normalized) at face coordinates (s, t) ∈ [−1, 1]²: the one
    /// face table of the crate (`ibl::cube` reads it too).
    #[inline]
    pub fn direction(self, s: f64, t: f64) -> DVec3 {
        match self {
            Face::PosX => DVec3::new(1.0, -t, -s),
            Face::NegX => DVec3::new(-1.0, -t, s),
            Face::PosY => DVec3::new(s, 1.0, t),
            Face::NegY => DVec3::new(s, -1.0, -t),
            Face::PosZ => DVec3::new(s, -t, 1.0),
            Face::NegZ => DVec3::new(-s, -t, -1.0),
        }
    }
}

/// World direction at continuous face position (px, py) ∈ [0, n]².
pub(crate) fn direction_at(face: Face, n: usize, px: f64, py: f64) -> DVec3 {
    let s = 2.0 * px / n as f64 - 1.0;
    let t = 2.0 * py / n as f64 - 1.0;
    (WORLD_FROM_CUBE * face.direction(s, t)).normalize()
}

/// Solid angle subtended by the face rectangle from (0,0) to (a,b) on the plane at distance 1:
/// atan2(ab, √(a²+b²+1)) (the standard cube-map texel solid angle identity).
fn area_element(a: f64, b: f64) -> f64 {
    (a * b).atan2((a * a + b * b + 1.0).sqrt())
}

/// Centre direction and exact solid angle of texel (x, y) of an n×n face.
pub(crate) fn texel(face: Face, n: usize, x: usize, y: usize) -> (DVec3, f64) {
    let h = 2.0 / n as f64;
    let (s0, t0) = (x as f64 * h - 1.0, y as f64 * h - 1.0);
    let (s1, t1) = (s0 + h, t0 + h);
    let omega = area_element(s1, t1) - area_element(s0, t1) - area_element(s1, t0) + area_element(s0, t0);
    (direction_at(face, n, x as f64 + 0.5, y as f64 + 0.5), omega)
}

/// The face a world direction hits and its face coordinates (s, t) ∈ [−1, 1]².
pub(crate) fn face_coords(dir: DVec3) -> (Face, f64, f64) {
    select_face(WORLD_FROM_CUBE.transpose() * dir)
}

/// The face a cube-frame direction selects and its face coordinates (s, t) ∈ [−1, 1]², by the
/// major-axis rule of the Vulkan/GL cube samplers (ties go to X, then Y): the inverse of
/// [`Face::direction`].
pub fn select_face(d: DVec3) -> (Face, f64, f64) {
    let (ax, ay, az) = (d.x.abs(), d.y.abs(), d.z.abs());
    if ax >= ay && ax >= az {
        if d.x > 0.0 {
            (Face::PosX, -d.z / ax, -d.y / ax)
        } else {
            (Face::NegX, d.z / ax, -d.y / ax)
        }
    } else if ay >= az {
        if d.y > 0.0 {
            (Face::PosY, d.x / ay, d.z / ay)
        } else {
            (Face::NegY, d.x / ay, -d.z / ay)
        }
    } else if d.z > 0.0 {
        (Face::PosZ, d.x / az, -d.y / az)
    } else {
        (Face::NegZ, -d.x / az, -d.y / az)
    }
}

/// Cell (column, row) of each face in a cross, in units of the face size, and whether it is
/// stored rotated by 180°.
fn cross_cell(layout: Layout, face: Face) -> (usize, usize, bool) {
    match (layout, face) {
        (_, Face::PosY) => (1, 0, false),
        (_, Face::NegX) => (0, 1, false),
        (_, Face::PosZ) => (1, 1, false),
        (_, Face::PosX) => (2, 1, false),
        (_, Face::NegY) => (1, 2, false),
        (Layout::CrossVertical, Face::NegZ) => (1, 3, true),
        (_, Face::NegZ) => (3, 1, false),
    }
}

/// Maps a cross pixel to (face, face x, face y), or `None` for the empty cells.
pub(crate) fn cross_to_face(layout: Layout, n: usize, x: usize, y: usize) -> Option<(Face, usize, usize)> {
    let (cx, cy) = (x / n, y / n);
    for face in FACES {
        let (col, row, rotated) = cross_cell(layout, face);
        if (col, row) == (cx, cy) {
            let (fx, fy) = (x - col * n, y - row * n);
            return Some(if rotated { (face, n - 1 - fx, n - 1 - fy) } else { (face, fx, fy) });
        }
    }
    None
}

/// Maps a face texel to its cross pixel.
pub(crate) fn face_to_cross(layout: Layout, n: usize, face: Face, fx: usize, fy: usize) -> (usize, usize) {
    let (col, row, rotated) = cross_cell(layout, face);
    let (fx, fy) = if rotated { (n - 1 - fx, n - 1 - fy) } else { (fx, fy) };
    (col * n + fx, row * n + fy)
}
