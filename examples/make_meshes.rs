//! Writes the small meshes of `testdata/meshes/`: a UV sphere with normals, a concave "bowl" (a
//! hemisphere shell open at the top, normals omitted so `render` computes them) and a (2, 3)
//! torus knot, a tube whose loops shadow each other, with exact normals.
//! Run: `cargo run --release --example make_meshes`.

use glam::DVec3;
use std::f64::consts::PI;
use std::fmt::Write;

/// The (p, q) torus knot's centre curve, scaled to fit the unit sphere.
fn knot(p: f64, q: f64, t: f64) -> DVec3 {
    let r = 2.0 + (q * t).cos();
    DVec3::new(r * (p * t).cos(), r * (p * t).sin(), -(q * t).sin()) / 3.2
}

/// A tube of radius `radius` around the (2, 3) torus knot: `segments` rings of `sides` vertices,
/// each ring in the curve's Frenet frame (well defined: the knot's curvature never vanishes, and
/// periodic, so the tube closes without a seam). Normals are exact: from the curve to the vertex.
fn torus_knot(segments: usize, sides: usize, radius: f64) -> (Vec<DVec3>, Vec<DVec3>, Vec<[usize; 3]>) {
    let (mut pos, mut nrm, mut tri) = (Vec::new(), Vec::new(), Vec::new());
    let h = 1e-4;
    for i in 0..segments {
        let t = 2.0 * PI * i as f64 / segments as f64;
        let c = knot(2.0, 3.0, t);
        let d1 = (knot(2.0, 3.0, t + h) - knot(2.0, 3.0, t - h)) / (2.0 * h);
        let d2 = (knot(2.0, 3.0, t + h) - 2.0 * c + knot(2.0, 3.0, t - h)) / (h * h);
        let tangent = d1.normalize();
        let normal = (d2 - d2.dot(tangent) * tangent).normalize();
        let binormal = tangent.cross(normal);
        for j in 0..sides {
            let a = 2.0 * PI * j as f64 / sides as f64;
            let n = a.cos() * normal + a.sin() * binormal;
            pos.push(c + radius * n);
            nrm.push(n);
        }
    }
    for i in 0..segments {
        for j in 0..sides {
            let v = |i: usize, j: usize| (i % segments) * sides + j % sides;
            // Counter-clockwise seen from outside: the face normals agree with the stored ones.
            tri.push([v(i, j), v(i + 1, j + 1), v(i + 1, j)]);
            tri.push([v(i, j), v(i, j + 1), v(i + 1, j + 1)]);
        }
    }
    (pos, nrm, tri)
}

fn main() -> std::io::Result<()> {
    let (p, t) = prtkit::render::mesh::uv_sphere(16, 32);
    let mut s = String::from("# UV sphere, 16 rings x 32 segments, unit radius, exact normals\n");
    for v in &p {
        let _ = writeln!(s, "v {:.6} {:.6} {:.6}", v.x, v.y, v.z);
    }
    for v in &p {
        let _ = writeln!(s, "vn {:.6} {:.6} {:.6}", v.x, v.y, v.z);
    }
    for f in &t {
        let _ = writeln!(s, "f {0}//{0} {1}//{1} {2}//{2}", f[0] + 1, f[1] + 1, f[2] + 1);
    }
    std::fs::write("testdata/meshes/sphere.obj", s)?;
    // Bowl: the lower half of the sphere (a cup opening towards +Z), no normals: concave inside,
    // so the inner wall shadows itself.
    let mut b = String::from("# lower hemisphere shell (a bowl opening to +Z), no normals\n");
    let keep: Vec<bool> = p.iter().map(|v| v.z <= 1e-9).collect();
    let mut map = vec![0usize; p.len()];
    let mut k = 0;
    for (i, v) in p.iter().enumerate() {
        if keep[i] {
            k += 1;
            map[i] = k;
            let _ = writeln!(b, "v {:.6} {:.6} {:.6}", v.x, v.y, v.z);
        }
    }
    for f in &t {
        if f.iter().all(|&i| keep[i as usize]) {
            // Reversed winding: the computed normals point into the bowl (its concave, lit side).
            let _ = writeln!(b, "f {} {} {}", map[f[0] as usize], map[f[2] as usize], map[f[1] as usize]);
        }
    }
    std::fs::write("testdata/meshes/bowl.obj", b)?;
    let (p, n, t) = torus_knot(160, 12, 0.11);
    let mut k = String::from("# (2,3) torus knot tube, 160 x 12 vertices, exact normals\n");
    for v in &p {
        let _ = writeln!(k, "v {:.5} {:.5} {:.5}", v.x, v.y, v.z);
    }
    for v in &n {
        let _ = writeln!(k, "vn {:.5} {:.5} {:.5}", v.x, v.y, v.z);
    }
    for f in &t {
        let _ = writeln!(k, "f {0}//{0} {1}//{1} {2}//{2}", f[0] + 1, f[1] + 1, f[2] + 1);
    }
    std::fs::write("testdata/meshes/torus-knot.obj", k)?;
    Ok(())
}
