//! glTF 2.0 input (issue 32): `transfer MESH` and `render --scene MESH` read `.gltf` and `.glb`
//! through `prtkit::io::gltf`, against oracles that do not use it.
//!
//! - A `.glb` that `transfer` wrote, baked again, gives the transfer of the OBJ it came from, bit
//!   for bit, once the OBJ's normals are taken to f32 as the `.glb` holds them.
//! - A hand-written scene (`testdata/meshes/tetrahedra.gltf`: one tetrahedron placed three times,
//!   by a translation, by T·R·S and by a mirroring child matrix) is placed as the transforms,
//!   written out here by hand, place it; the same scene with an interleaved external `.bin` is read
//!   to the same bits.
//! - Bad assets exit 2 naming the file and the object, and write nothing.

mod common;

use common::{cmd, stderr};
use glam::DVec3;
use prtkit::mesh::Mesh;
use prtkit::progress::NoProgress;
use prtkit::transfer::stage::{self, Config, Mode};
use std::path::{Path, PathBuf};

fn meshes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("testdata/meshes")
}

fn bits(v: &[DVec3]) -> Vec<[u64; 3]> {
    v.iter().map(|p| p.to_array().map(f64::to_bits)).collect()
}

#[test]
fn a_glb_written_by_transfer_bakes_to_the_transfer_of_its_obj() {
    let dir = tempfile::tempdir().unwrap();
    let obj = meshes().join("torus-knot.obj");
    let bake = ["-n", "3", "--rays", "64", "-q"];
    cmd("transfer")
        .arg(&obj)
        .args(bake)
        .args(["--glb", "a.glb", "-o", "a.json"])
        .current_dir(dir.path())
        .assert()
        .success();
    cmd("transfer")
        .arg("a.glb")
        .args(bake)
        .args(["--glb", "b.glb", "-o", "b.json"])
        .current_dir(dir.path())
        .assert()
        .success();

    // The OBJ as the .glb holds it: positions are f32 in both, normals are the OBJ's unit normals
    // taken to f32 (then normalized again, as any file's normals are).
    let from_obj = Mesh::load(&obj).unwrap();
    let rounded = from_obj.normals.iter().map(|n| n.as_vec3().as_dvec3()).collect();
    let oracle = Mesh::new(from_obj.positions.clone(), Some(rounded), from_obj.triangles.clone()).unwrap();
    let from_glb = Mesh::load(&dir.path().join("a.glb")).unwrap();
    assert!(!from_glb.normals_computed);
    assert_eq!(from_glb.triangles, oracle.triangles);
    assert!(bits(&from_glb.positions) == bits(&oracle.positions), "positions differ");
    assert!(bits(&from_glb.normals) == bits(&oracle.normals), "normals differ");

    let config = Config { order: 3, rays: 64, mode: Mode::Shadowed, ..Config::default() };
    let want = stage::run(&config, &oracle, &NoProgress).unwrap();
    let got = stage::run(&config, &from_glb, &NoProgress).unwrap();
    assert!(got.transfer.iter().map(|x| x.to_bits()).eq(want.transfer.iter().map(|x| x.to_bits())), "transfer differs");
    // The binary's bake of a.glb holds the same bytes: positions, normals, transfer, indices.
    let b = std::fs::read(dir.path().join("b.glb")).unwrap();
    assert!(prtkit::io::glb::bin_chunk(&b) == prtkit::io::glb::bin_chunk(&want.glb), "b.glb's buffer differs");
    let doc: serde_json::Value = common::read(&dir.path().join("b.json"));
    assert_eq!(doc["mesh"]["normals"], "file");

    // Against the OBJ's own bake, the f32 rounding of the normals is all that differs.
    let a = std::fs::read(dir.path().join("a.glb")).unwrap();
    let floats = |glb: &[u8]| -> Vec<f32> {
        prtkit::io::glb::bin_chunk(glb)
            .unwrap()
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
            .collect()
    };
    let n = from_obj.positions.len();
    let (fa, fb) = (floats(&a), floats(&b));
    // POSITION (3n floats), NORMAL (3n), then the transfer; the indices (u32) after it.
    let transfer = 6 * n..6 * n + 12 * n;
    let worst = fa[transfer.clone()].iter().zip(&fb[transfer]).map(|(x, y)| (x - y).abs()).fold(0f32, f32::max);
    eprintln!("torus knot: OBJ bake vs its .glb baked again: largest transfer difference {worst:.2e}");
    assert!(fa[..3 * n] == fb[..3 * n] && worst < 1e-6, "{worst}");
}

/// The tetrahedron of the fixture, its vertices' normals (from the centroid, as f32) and its
/// triangles, counter-clockwise seen from outside.
fn tetrahedron() -> ([DVec3; 4], [DVec3; 4], [[u32; 3]; 4]) {
    let p = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
    let n = p.map(|v| (v - DVec3::splat(0.25)).normalize().as_vec3().as_dvec3());
    (p, n, [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
}

/// The fixture's three copies, each as (place a position, turn a normal, winding turned), written
/// out from the glTF's definitions (§3.5.2: a node's local transform is T·R·S or its matrix; the
/// child is placed by its parent's transform times its own) without a matrix library:
/// - node 0: translation (2, 0, 0);
/// - node 1: translation (0, 0, −3), rotation 90° about +Y ((x, y, z) → (z, y, −x)), scale
///   (1, 2, 0.5);
/// - node 2, node 1's child: the matrix x → −x, y → y + 1 (a mirror: its winding is turned).
///
/// Normals go by the inverse transpose: R·S⁻¹ (R is orthonormal), and for the mirror also x → −x.
#[allow(clippy::type_complexity)]
fn copies() -> [(fn(DVec3) -> DVec3, fn(DVec3) -> DVec3, bool); 3] {
    fn rot(v: DVec3) -> DVec3 {
        DVec3::new(v.z, v.y, -v.x)
    }
    fn node1(p: DVec3) -> DVec3 {
        rot(p * DVec3::new(1.0, 2.0, 0.5)) + DVec3::new(0.0, 0.0, -3.0)
    }
    [
        (|p| p + DVec3::new(2.0, 0.0, 0.0), |n| n, false),
        (node1, |n| rot(n / DVec3::new(1.0, 2.0, 0.5)), false),
        (
            |p| node1(DVec3::new(-p.x, p.y + 1.0, p.z)),
            |n| rot(DVec3::new(-n.x, n.y, n.z) / DVec3::new(1.0, 2.0, 0.5)),
            true,
        ),
    ]
}

#[test]
fn a_hand_written_scene_is_placed_node_by_node() {
    let (p, n, t) = tetrahedron();
    let mesh = Mesh::load(&meshes().join("tetrahedra.gltf")).unwrap();
    // The default scene (`scene`: 1) has nodes 0 and 1, and 1 has child 2; scene 0 only node 0.
    assert_eq!((mesh.positions.len(), mesh.triangles.len()), (12, 12));
    assert!(!mesh.normals_computed);
    for (copy, (place, turn, mirrored)) in copies().into_iter().enumerate() {
        for k in 0..4 {
            let (got, want) = (mesh.positions[4 * copy + k], place(p[k]));
            assert!((got - want).length() < 1e-12, "copy {copy}, vertex {k}: {got} vs {want}");
            let (got, want) = (mesh.normals[4 * copy + k], turn(n[k]).normalize());
            assert!((got - want).length() < 1e-12, "copy {copy}, normal {k}: {got} vs {want}");
        }
        let centre = (0..4).map(|k| place(p[k])).sum::<DVec3>() / 4.0;
        for (j, tri) in t.iter().enumerate() {
            let [a, b, c] = mesh.triangles[4 * copy + j].map(|i| mesh.positions[i as usize]);
            // Every face of every copy faces out, the mirrored one too (its winding turned back).
            assert!((b - a).cross(c - a).dot((a + b + c) / 3.0 - centre) > 0.0, "copy {copy}, face {j}");
            let mut want = tri.map(|i| 4 * copy as u32 + i);
            if mirrored {
                want.swap(1, 2);
            }
            assert_eq!(mesh.triangles[4 * copy + j], want);
        }
    }
    // The same scene, interleaved (byteStride 24) in an external .bin: the same bits.
    let external = Mesh::load(&meshes().join("tetrahedra-bin.gltf")).unwrap();
    assert!(bits(&external.positions) == bits(&mesh.positions) && bits(&external.normals) == bits(&mesh.normals));
    assert_eq!(external.triangles, mesh.triangles);

    // Without NORMAL the normals are computed, as an OBJ's would be.
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(meshes().join("tetrahedra.gltf")).unwrap();
    let bare = dir.path().join("bare.GLTF");
    std::fs::write(&bare, text.replace(", \"NORMAL\": 1", "")).unwrap();
    let computed = Mesh::load(&bare).unwrap();
    assert!(computed.normals_computed && bits(&computed.positions) == bits(&mesh.positions));

    // An asset that requires extensions of materials and textures alone is read; one that
    // requires a compression of its geometry is refused (below).
    let textured = dir.path().join("textured.glTF");
    let extended = text.replacen(
        "\"scene\": 1,",
        "\"scene\": 1, \"extensionsUsed\": [\"KHR_texture_basisu\", \"KHR_materials_unlit\"],\n \"extensionsRequired\": [\"KHR_texture_basisu\", \"KHR_materials_unlit\"],\n \"textures\": [{\"extensions\": {\"KHR_texture_basisu\": {\"source\": 0}}}],",
        1,
    );
    assert_ne!(extended, text);
    std::fs::write(&textured, extended).unwrap();
    assert!(bits(&Mesh::load(&textured).unwrap().positions) == bits(&mesh.positions));

    // And through the binaries: transfer bakes it, render draws it.
    let out = cmd("transfer")
        .arg(meshes().join("tetrahedra.gltf"))
        .args(["--mode", "unshadowed", "--glb", "t.glb", "-o", "t.json"])
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let doc: serde_json::Value = common::read(&dir.path().join("t.json"));
    assert_eq!((doc["mesh"]["vertices"].as_u64(), doc["mesh"]["normals"].as_str()), (Some(12), Some("file")));
    common::sky_pfm(dir.path(), 16, 8);
    let out = cmd("render")
        .args(["sky.pfm", "--scene", bare.to_str().unwrap(), "--res", "16x16", "-o", "r.exr", "--eye", "6,6,6"])
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stderr(&out).contains("bare.GLTF: no vertex normals in the file"), "{}", stderr(&out));
}

/// A one-triangle asset in `dir`: `name` (JSON, `{json}` spliced into its primitive's document)
/// and `name`.bin holding `positions` then u16 `indices`. `edit` changes the JSON text.
fn write_asset(
    dir: &Path,
    name: &str,
    positions: &[[f32; 3]],
    indices: &[u16],
    edit: impl Fn(String) -> String,
) -> PathBuf {
    let mut bin: Vec<u8> = positions.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
    let at = bin.len();
    bin.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    let bin_name = format!("{name}.bin");
    std::fs::write(dir.join(&bin_name), &bin).unwrap();
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scenes": [{{"nodes": [0]}}], "nodes": [{{"mesh": 0}}],
 "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1}}]}}],
 "accessors": [{{"bufferView": 0, "componentType": 5126, "count": {}, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 1]}},
  {{"bufferView": 1, "componentType": 5123, "count": {}, "type": "SCALAR"}}],
 "bufferViews": [{{"buffer": 0, "byteLength": {at}}}, {{"buffer": 0, "byteOffset": {at}, "byteLength": {}}}],
 "buffers": [{{"byteLength": {}, "uri": "{bin_name}"}}]}}"#,
        positions.len(),
        indices.len(),
        bin.len() - at,
        bin.len()
    );
    let path = dir.join(name);
    std::fs::write(&path, edit(json)).unwrap();
    path
}

#[test]
fn bad_assets_exit_2_naming_the_file_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let tri = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let same = |s: String| s;
    // A good asset first, so that each case below is wrong by its one edit.
    let good = write_asset(d, "good.gltf", &tri, &[0, 1, 2], same);
    cmd("transfer")
        .arg(&good)
        .args(["--mode", "unshadowed", "-q", "--glb", "g.glb", "-o", "g.json"])
        .current_dir(d)
        .assert()
        .success();
    let glb = std::fs::read(d.join("g.glb")).unwrap();
    std::fs::remove_file(d.join("g.glb")).unwrap();
    std::fs::remove_file(d.join("g.json")).unwrap();
    let write = |name: &str, bytes: &[u8]| {
        std::fs::write(d.join(name), bytes).unwrap();
        d.join(name)
    };
    let cases: Vec<(PathBuf, &str)> = vec![
        (write("cut.glb", &glb[..glb.len() / 2]), "truncated: the GLB header gives"),
        (write("text.glb", b"hello"), "does not start like glTF"),
        (write("junk.gltf", b"{ \"asset\": "), "not a valid glTF 2.0 asset"),
        (
            write_asset(d, "index.gltf", &tri, &[0, 1, 7], same),
            "mesh 0, primitive 0: index 7 is out of range (3 vertices)",
        ),
        (
            write_asset(d, "nan.gltf", &[[f32::NAN, 0.0, 0.0], tri[1], tri[2]], &[0, 1, 2], same),
            "a POSITION is not finite",
        ),
        (write_asset(d, "gone.gltf", &tri, &[0, 1, 2], |s| s.replace("gone.gltf.bin", "nowhere.bin")), "buffer 0: "),
        (
            write_asset(d, "short.gltf", &tri, &[0, 1, 2], |s| {
                s.replace("\"byteLength\": 42, \"uri\"", "\"byteLength\": 400, \"uri\"")
            }),
            "buffer 0: it holds 42 bytes, fewer than its byteLength 400",
        ),
        (
            write_asset(d, "view.gltf", &tri, &[0, 1, 2], |s| {
                s.replace("\"byteOffset\": 36, \"byteLength\": 6", "\"byteOffset\": 38, \"byteLength\": 6")
            }),
            "buffer view 1 (bytes 38..38+6) runs past the end of buffer 0 (42 bytes)",
        ),
        (
            write_asset(d, "lines.gltf", &tri, &[0, 1, 2], |s| {
                s.replace("\"indices\": 1", "\"indices\": 1, \"mode\": 1")
            }),
            "mode Lines draws points or lines",
        ),
        (
            write_asset(d, "nopos.gltf", &tri, &[0, 1, 2], |s| s.replace("\"POSITION\": 0", "\"NORMAL\": 0")),
            "mesh 0, primitive 0: no POSITION attribute",
        ),
        (
            write_asset(d, "sparse.gltf", &tri, &[0, 1, 2], |s| {
                s.replace("\"count\": 3, \"type\": \"VEC3\"", "\"count\": 3, \"type\": \"VEC3\", \"sparse\": {\"count\": 1, \"indices\": {\"bufferView\": 1, \"componentType\": 5123}, \"values\": {\"bufferView\": 0}}")
            }),
            "accessor 0 is sparse, which prtkit does not read",
        ),
        (
            write_asset(d, "cycle.gltf", &tri, &[0, 1, 2], |s| {
                s.replace(
                    "\"nodes\": [{\"mesh\": 0}]",
                    "\"nodes\": [{\"mesh\": 0, \"children\": [1]}, {\"children\": [0]}]",
                )
            }),
            "node 0: is reached twice",
        ),
        (
            write_asset(d, "flat.gltf", &tri, &[0, 1, 2], |s| {
                s.replace("\"nodes\": [{\"mesh\": 0}]", "\"nodes\": [{\"mesh\": 0, \"scale\": [1, 0, 1]}]")
            }),
            "node 0: the world transform is singular",
        ),
        (
            write_asset(d, "draco.gltf", &tri, &[0, 1, 2], |s| {
                s.replacen("{", "{\"extensionsRequired\": [\"KHR_draco_mesh_compression\"], ", 1)
            }),
            "extensionsRequired[0] = \"KHR_draco_mesh_compression\": Unsupported extension",
        ),
        (
            write_asset(d, "absolute.gltf", &tri, &[0, 1, 2], |s| s.replace("absolute.gltf.bin", "/dev/zero")),
            "\"/dev/zero\" is not a relative path or a data: URI",
        ),
    ];
    for (mesh, reason) in cases {
        let output =
            cmd("transfer").arg(&mesh).args(["--glb", "out.glb", "-o", "out.json"]).current_dir(d).output().unwrap();
        let message = stderr(&output);
        let name = mesh.display().to_string();
        assert_eq!(output.status.code(), Some(2), "{name}: {message}");
        assert!(message.contains(&name) && message.contains(reason), "{name}: expected {reason:?}: {message}");
        assert!(!d.join("out.glb").exists() && !d.join("out.json").exists(), "{name}: an output was written");
    }
    // The missing buffer is named beside the asset.
    let output = cmd("transfer")
        .arg(d.join("gone.gltf"))
        .args(["--glb", "out.glb", "-o", "out.json"])
        .current_dir(d)
        .output()
        .unwrap();
    assert!(stderr(&output).contains("nowhere.bin"), "{}", stderr(&output));
}
