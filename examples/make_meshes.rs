//! Writes the small meshes of `testdata/meshes/`: a UV sphere with normals and a concave
//! "bowl" (a hemisphere shell open at the top, normals omitted so `render` computes them).
//! Run: `cargo run --release --example make_meshes`.

use std::fmt::Write;

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
    Ok(())
}
