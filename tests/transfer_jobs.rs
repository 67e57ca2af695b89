//! `transfer --job I/N` and `--join` (issue 32, "Scale"): a bake split into jobs whose parts,
//! joined in any order, give one run's outputs byte for byte — diffuse shadowed with clustered
//! PCA, quantization and a lightmap applied at the join, a coloured albedo, glossy shadowed, and across thread
//! counts — and parts that do not belong, or leave vertices out, are refused naming the file.

mod common;

use common::{cmd, run_in, stderr, test_mesh};
use std::path::Path;

/// Runs `transfer MESH base… extra…` in `dir`, asserting success.
fn transfer(dir: &Path, base: &[&str], extra: &[&str]) {
    run_in(dir, "transfer", &[base, extra].concat());
}

/// Bakes `base` in one run into `one.*` and in `n` jobs joined (in reverse order) into
/// `joined.*`, with `finish` (options of the join only) on both; asserts the `.glb`, the GLSL
/// and, when asked, the lightmap are the same bytes and the manifests differ only in provenance.
fn one_run_and_jobs_agree(dir: &Path, base: &[&str], finish: &[&str], n: usize, threads: [&str; 2], lightmap: bool) {
    let with = |tag: &str| {
        let mut v: Vec<String> = ["--glb", &format!("{tag}.glb"), "-o", &format!("{tag}.json"), "--glsl"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        v.push(format!("{tag}.glsl"));
        if lightmap {
            v.extend(["--lightmap".into(), "32x32".into(), format!("{tag}.exr")]);
        }
        v.extend(finish.iter().map(|s| s.to_string()));
        v
    };
    let one = with("one");
    let one: Vec<&str> = one.iter().map(String::as_str).collect();
    transfer(dir, base, &[&one[..], &["--threads", threads[0]]].concat());
    let parts: Vec<String> = (1..=n).map(|i| format!("p{i}.part")).collect();
    for (i, part) in parts.iter().enumerate() {
        let job = format!("{}/{n}", i + 1);
        transfer(dir, base, &["--job", &job, part, "--threads", threads[1]]);
    }
    let mut join: Vec<&str> = vec!["--join"];
    join.extend(parts.iter().rev().map(String::as_str));
    let joined = with("joined");
    join.extend(joined.iter().map(String::as_str));
    transfer(dir, base, &join);
    let bytes = |name: &str| std::fs::read(dir.join(name)).unwrap();
    assert!(bytes("one.glb") == bytes("joined.glb"), "{base:?} {finish:?}: the joined .glb differs");
    assert!(bytes("one.glsl") == bytes("joined.glsl"), "{base:?} {finish:?}: the joined GLSL differs");
    if lightmap {
        assert!(bytes("one.exr") == bytes("joined.exr"), "{base:?}: the joined lightmap differs");
    }
    let body = |name: &str| {
        let mut v: serde_json::Value = common::read(&dir.join(name));
        let o = v.as_object_mut().unwrap();
        o.remove("provenance");
        o["glb"]["file"] = "".into();
        if let Some(l) = o.get_mut("lightmap") {
            l["file"] = "".into();
        }
        v
    };
    assert_eq!(body("one.json"), body("joined.json"), "{base:?} {finish:?}");
}

#[test]
fn diffuse_jobs_join_into_one_runs_bytes() {
    let dir = tempfile::tempdir().unwrap();
    // Shadowed: the parts carry the estimates of the manifest's error figures too; the lightmap
    // (of a mesh with UVs) is baked at the join.
    let floor = test_mesh("floor-ball.obj");
    one_run_and_jobs_agree(dir.path(), &[floor.as_str(), "-n", "4", "--rays", "64"], &[], 3, ["2", "1"], true);
    let mesh = test_mesh("bowl-ball.obj");
    let base = [mesh.as_str(), "-n", "4", "--rays", "64"];
    one_run_and_jobs_agree(
        dir.path(),
        &base,
        &["--clusters", "8", "--pca", "4", "--quantize", "i8"],
        5,
        ["1", "2"],
        false,
    );
    // A coloured albedo: the parts hold the grey transfer at albedo 1, and the join makes the
    // channels (and the coloured lightmap) as one run does.
    let coloured = [floor.as_str(), "-n", "3", "--rays", "64", "--albedo", "0.9,0.5,0.2"];
    one_run_and_jobs_agree(dir.path(), &coloured, &["--quantize", "i16"], 2, ["1", "2"], true);
    let unshadowed = [mesh.as_str(), "-n", "3", "--mode", "unshadowed"];
    one_run_and_jobs_agree(dir.path(), &unshadowed, &["--quantize", "i16"], 2, ["2", "2"], false);
}

#[test]
fn glossy_jobs_join_into_one_runs_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let factors = ["phong:s=8", "--domain", "hemisphere", "--resolution", "8", "--cosine", "--factors", "p.exr"];
    run_in(d, "factor-brdf", &[&factors[..], &["--terms", "4", "-o", "p.json"]].concat());
    let mesh = test_mesh("bowl-ball.obj");
    let base = [mesh.as_str(), "-n", "3", "--factors", "p.json", "-K", "3"];
    one_run_and_jobs_agree(d, &base, &[], 4, ["2", "1"], false);
}

/// Runs `transfer` in `dir`, expecting exit 2 with `message` on stderr.
fn refused(dir: &Path, args: &[&str], message: &str) {
    let out = cmd("transfer").args(args).current_dir(dir).output().unwrap();
    assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
    assert!(stderr(&out).contains(message), "{args:?}: {}", stderr(&out));
}

#[test]
fn parts_that_do_not_belong_or_leave_vertices_out_are_refused_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mesh = test_mesh("bowl-ball.obj");
    let base = [mesh.as_str(), "-n", "3", "--rays", "16"];
    for i in 1..=3 {
        transfer(d, &base, &["--job", &format!("{i}/3"), &format!("p{i}.part")]);
    }
    transfer(d, &[mesh.as_str(), "-n", "3", "--rays", "32"], &["--job", "2/3", "rays32.part"]);
    std::fs::write(d.join("junk.part"), b"PRTKPART\x02\x00\x00\x00{}").unwrap();
    let out = ["--glb", "j.glb", "-o", "j.json"];
    let cases: [(&[&str], &str); 6] = [
        (&["p1.part", "p3.part"], "no part holds vertices"),
        (
            &["p1.part", "rays32.part", "p3.part"],
            "rays32.part: not a part of this bake: baked with rays = 32, where this join has 16",
        ),
        (&["p1.part", "p2.part", "p2.part", "p3.part"], "p2.part: its vertices"),
        (&["p1.part", "junk.part"], "junk.part: its header"),
        (&["p1.part", "absent.part"], "absent.part"),
        (&["p1.part", "j.json"], "j.json"),
    ];
    std::fs::write(d.join("j.json"), "{}").unwrap();
    for (parts, message) in cases {
        let args = [&base[..], &["--join"], parts, &out].concat();
        let glb_before = d.join("j.glb").exists();
        refused(d, &args, message);
        assert!(!glb_before && !d.join("j.glb").exists(), "{parts:?}: wrote the .glb");
    }
    // A job of an interreflected bake, and bad job numbers.
    let inter = [mesh.as_str(), "--mode", "interreflected", "--rays", "16", "--job", "1/2", "i.part"];
    refused(d, &inter, "interreflected transfer is baked in one run");
    refused(d, &[&base[..], &["--job", "4/3", "x.part"]].concat(), "a job is I/N with 1 <= I <= N");
    refused(d, &[&base[..], &["--job", "1/3", "x.glb"]].concat(), "must end in .part");
    assert!(!d.join("i.part").exists() && !d.join("x.part").exists());
}
