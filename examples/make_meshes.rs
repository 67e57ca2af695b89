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

/// An OBJ file: a comment line, `v` lines with `decimals` digits, `vn` lines when normals are
/// given, and 1-based faces (`f a//a …` with normals, `f a …` without).
fn obj(header: &str, positions: &[DVec3], normals: Option<&[DVec3]>, faces: &[[usize; 3]], decimals: usize) -> String {
    let mut s = format!("# {header}\n");
    for (tag, vs) in [("v", Some(positions)), ("vn", normals)] {
        for v in vs.unwrap_or_default() {
            let _ = writeln!(s, "{tag} {:.*} {:.*} {:.*}", decimals, v.x, decimals, v.y, decimals, v.z);
        }
    }
    for f in faces {
        let [a, b, c] = f.map(|i| i + 1);
        let _ = match normals {
            Some(_) => writeln!(s, "f {a}//{a} {b}//{b} {c}//{c}"),
            None => writeln!(s, "f {a} {b} {c}"),
        };
    }
    s
}

fn main() -> std::io::Result<()> {
    let (p, t) = prtkit::mesh::uv_sphere(16, 32);
    let t: Vec<[usize; 3]> = t.iter().map(|f| f.map(|i| i as usize)).collect();
    let header = "UV sphere, 16 rings x 32 segments, unit radius, exact normals";
    std::fs::write("testdata/meshes/sphere.obj", obj(header, &p, Some(&p), &t, 6))?;
    // Bowl: the lower half of the sphere (a cup opening towards +Z), no normals: concave inside,
    // so the inner wall shadows itself.
    let keep: Vec<usize> = (0..p.len()).filter(|&i| p[i].z <= 1e-9).collect();
    let mut map = vec![usize::MAX; p.len()];
    for (new, &old) in keep.iter().enumerate() {
        map[old] = new;
    }
    let bowl: Vec<DVec3> = keep.iter().map(|&i| p[i]).collect();
    // Reversed winding: the computed normals point into the bowl (its concave, lit side).
    let faces: Vec<[usize; 3]> = t
        .iter()
        .filter(|f| f.iter().all(|&i| map[i] != usize::MAX))
        .map(|f| [map[f[0]], map[f[2]], map[f[1]]])
        .collect();
    let header = "lower hemisphere shell (a bowl opening to +Z), no normals";
    std::fs::write("testdata/meshes/bowl.obj", obj(header, &bowl, None, &faces, 6))?;
    // Bowl holding a ball (docs/transfer.md's relit picture): a finer bowl with exact normals
    // into its inside, and a ball of radius 0.35 resting just above its floor off the axis, so
    // that the ball shadows the bowl, the bowl the ball, and light bounces between them.
    let (p, t) = prtkit::mesh::uv_sphere(32, 64);
    let keep: Vec<usize> = (0..p.len()).filter(|&i| p[i].z <= 1e-9).collect();
    let mut map = vec![usize::MAX; p.len()];
    for (new, &old) in keep.iter().enumerate() {
        map[old] = new;
    }
    let mut pos: Vec<DVec3> = keep.iter().map(|&i| p[i]).collect();
    let mut nrm: Vec<DVec3> = pos.iter().map(|v| -*v).collect();
    let mut faces: Vec<[usize; 3]> = t
        .iter()
        .map(|f| f.map(|i| i as usize))
        .filter(|f| f.iter().all(|&i| map[i] != usize::MAX))
        .map(|f| [map[f[0]], map[f[2]], map[f[1]]])
        .collect();
    let (bp, bt) = prtkit::mesh::uv_sphere(16, 32);
    let base = pos.len();
    let centre = DVec3::new(0.2, 0.0, -0.6);
    pos.extend(bp.iter().map(|v| centre + 0.35 * *v));
    nrm.extend(bp.iter().copied());
    faces.extend(bt.iter().map(|f| f.map(|i| i as usize + base)));
    let header = "bowl (lower unit hemisphere, 32 x 64 sphere's half, normals inward) holding a ball (radius 0.35 at 0.2,0,-0.6, 16 x 32)";
    std::fs::write("testdata/meshes/bowl-ball.obj", obj(header, &pos, Some(&nrm), &faces, 6))?;
    let (p, n, t) = torus_knot(160, 12, 0.11);
    let header = "(2,3) torus knot tube, 160 x 12 vertices, exact normals";
    std::fs::write("testdata/meshes/torus-knot.obj", obj(header, &p, Some(&n), &t, 5))?;
    Ok(())
}
