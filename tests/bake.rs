//! `examples/bake/Makefile` (docs/bake.md) as a real project would use it: a parallel bake, a
//! second make with nothing to do, an edited input that rebuilds exactly its dependents, a bake
//! interrupted half-way that leaves nothing make would take for up to date, and the same bytes
//! at `-j1` as at `-j2`. Skipped with a message when `make` is not installed.

#![cfg(unix)]

mod common;

use std::collections::{BTreeMap, BTreeSet};
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant, SystemTime};

fn repo() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn have_make() -> bool {
    Command::new("make").arg("--version").output().is_ok_and(|o| o.status.success())
}

/// A scratch clone holding what the Makefile reads: `examples/bake` (without outputs) and the
/// three files of `testdata/` it names. Returns the root; the bake runs in `root/examples/bake`.
fn clone() -> tempfile::TempDir {
    let root = tempfile::tempdir().unwrap();
    let copy = |from: &Path, to: &Path| {
        std::fs::create_dir_all(to.parent().unwrap()).unwrap();
        std::fs::copy(from, to).unwrap_or_else(|e| panic!("{}: {e}", from.display()));
    };
    common::copy_tree(&repo().join("examples/bake"), &root.path().join("examples/bake"), &["out"]);
    for data in ["shaders/sky.sl", "shaders/wood.sl", "meshes/torus-knot.obj"] {
        copy(&repo().join("testdata").join(data), &root.path().join("testdata").join(data));
    }
    root
}

/// `make ARGS` in the clone's bake directory, with the stages on PATH.
fn make(root: &Path, args: &[&str]) -> Command {
    let mut cmd = Command::new("make");
    cmd.args(args).current_dir(root.join("examples/bake")).env("PATH", common::path_with_stages());
    cmd
}

fn run(root: &Path, args: &[&str]) -> Output {
    let out = make(root, args).output().unwrap();
    assert!(out.status.success(), "make {args:?}: {:?}\n{}", out.status, String::from_utf8_lossy(&out.stderr));
    out
}

/// Every file of `out/`: name → (bytes, modification time). Polled while a bake runs, a file
/// listed may be gone when it is read (a stage's temporary file, renamed into place): skipped.
fn outputs(root: &Path) -> BTreeMap<String, (Vec<u8>, SystemTime)> {
    let dir = root.join("examples/bake/out");
    let Ok(entries) = std::fs::read_dir(&dir) else { return BTreeMap::new() };
    entries
        .filter_map(|e| {
            let e = e.unwrap();
            let path: PathBuf = e.path();
            let gone = |e: &std::io::Error| e.kind() == std::io::ErrorKind::NotFound;
            let modified = match e.metadata() {
                Err(err) if gone(&err) => return None,
                m => m.unwrap().modified().unwrap(),
            };
            let bytes = match std::fs::read(&path) {
                Err(err) if gone(&err) => return None,
                b => b.unwrap(),
            };
            Some((e.file_name().to_string_lossy().into_owned(), (bytes, modified)))
        })
        .collect()
}

/// How many entries `examples/bake/out` holds: the poll while a bake runs, which must not read
/// the outputs' bytes (reading them every few milliseconds slowed a loaded machine until the
/// bake finished before the signal could interrupt it).
fn output_count(root: &Path) -> usize {
    std::fs::read_dir(root.join("examples/bake/out")).map_or(0, |entries| entries.count())
}

fn bytes(files: &BTreeMap<String, (Vec<u8>, SystemTime)>) -> BTreeMap<&str, &[u8]> {
    files.iter().map(|(name, (data, _))| (name.as_str(), data.as_slice())).collect()
}

/// Sets the modification time of `path` to now, as `touch` does.
fn touch(path: &Path) {
    std::fs::File::options().append(true).open(path).unwrap().set_modified(SystemTime::now()).unwrap();
}

#[test]
fn the_bake_makefile_rebuilds_what_changed_survives_an_interruption_and_is_deterministic() {
    if !have_make() {
        eprintln!("skipped: `make` is not installed");
        return;
    }
    // A parallel bake: every stage, 40 files.
    let a = clone();
    let start = Instant::now();
    run(a.path(), &["-j2"]);
    eprintln!("make -j2: {:.1} s", start.elapsed().as_secs_f64());
    let baked = outputs(a.path());
    for stage_output in ["noon.exr", "dusk.png", "noon.sh.json", "dusk-brushed.exr", "plastic.factor.exr"] {
        assert!(baked.contains_key(stage_output), "no {stage_output} in {:?}", baked.keys());
    }
    for also in
        ["terms.svg", "noon-matte.png", "dusk-plastic.png", "mesh.codes", "texture.exr", "mesh.glb", "mesh-4.part"]
    {
        assert!(baked.contains_key(also), "no {also} in {:?}", baked.keys());
    }
    assert!(!baked.keys().any(|n| n.contains(".prtkit-")), "temporary files: {:?}", baked.keys());

    // Nothing to do the second time: `make -q` says up to date, and a make changes nothing.
    assert_eq!(make(a.path(), &["-q"]).status().unwrap().code(), Some(0), "make -q after a bake");
    run(a.path(), &["-j2"]);
    assert_eq!(outputs(a.path()), baked, "a second make rebuilt something");

    // An edited input (dusk's parameters) rebuilds its dependents and nothing else.
    std::thread::sleep(Duration::from_millis(20));
    touch(&a.path().join("examples/bake/envs/dusk.params"));
    run(a.path(), &["-j2"]);
    let after = outputs(a.path());
    let rebuilt: BTreeSet<&str> =
        after.iter().filter(|(name, (_, t))| baked[*name].1 != *t).map(|(name, _)| name.as_str()).collect();
    let dependents: BTreeSet<&str> = baked.keys().map(String::as_str).filter(|n| n.starts_with("dusk")).collect();
    assert_eq!(rebuilt, dependents, "touching envs/dusk.params");
    assert_eq!(dependents.len(), 12, "dusk's environment, preview, SH, 3 maps, 3 documents, 3 renders");
    assert_eq!(bytes(&after), bytes(&baked), "the same inputs baked again");

    // Interrupted half-way by SIGINT or SIGTERM to make's process group (what ^C does): every
    // target left is whole (the bytes of a complete bake), no temporary file, and a make
    // afterwards finishes the same bake.
    for signal in ["-INT", "-TERM"] {
        let b = clone();
        let mut child = make(b.path(), &["-j2"]).process_group(0).spawn().unwrap();
        let start = Instant::now();
        while output_count(b.path()) < 4 && child.try_wait().unwrap().is_none() {
            assert!(start.elapsed() < Duration::from_secs(120), "no outputs after 2 minutes");
            std::thread::sleep(Duration::from_millis(5));
        }
        let group = format!("-{}", child.id());
        let killed = Command::new("kill").args([signal, "--", &group]).status().unwrap();
        assert!(killed.success(), "kill {signal} -- {group}");
        let status = child.wait().unwrap();
        assert!(!status.success(), "make {signal}: {status:?}: the bake finished before the signal");
        // make has gone, but a stage run by a recipe's shell may still be cleaning up.
        let start = Instant::now();
        while Command::new("kill")
            .args(["-0", "--", &group])
            .stderr(std::process::Stdio::null())
            .status()
            .unwrap()
            .success()
        {
            assert!(start.elapsed() < Duration::from_secs(30), "{signal}: the stages still run 30 s after make");
            std::thread::sleep(Duration::from_millis(10));
        }
        let left = outputs(b.path());
        assert!(left.len() < baked.len(), "{signal}: every output is there: nothing was interrupted");
        assert!(!left.keys().any(|n| n.contains(".prtkit-")), "{signal}: temporary files: {:?}", left.keys());
        for (name, (data, _)) in &left {
            assert!(&baked[name].0 == data, "{signal}: {name} is not the whole output");
        }
        eprintln!("{signal}: {} of {} outputs written before the signal", left.len(), baked.len());
        run(b.path(), &["-j2"]);
        assert_eq!(bytes(&outputs(b.path())), bytes(&baked), "{signal}: the bake resumed");
    }

    // One job at a time: the same bytes.
    let c = clone();
    run(c.path(), &["-j1"]);
    assert_eq!(bytes(&outputs(c.path())), bytes(&baked), "make -j1 against make -j2");
}
