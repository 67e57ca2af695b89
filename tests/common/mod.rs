//! What the integration tests share: a stage's binary, one synthetic sky (and any lat-long map
//! of a function), one set of normals, writing images as PFM or EXR, the prefilter → render
//! chain, and reading JSON outputs into the library's types.

// Each test binary compiles this module and uses a part of it.
#![allow(dead_code)]

use assert_cmd::Command;
use glam::DVec3;
use prtkit::envmap::EnvMap;
use prtkit::io::{pfm, RgbImage};
use serde::de::DeserializeOwned;
use std::path::{Path, PathBuf};

/// The binary of `stage` (`sh-project`, `prefilter`, …, or the umbrella `prtkit`).
pub fn cmd(stage: &str) -> Command {
    Command::cargo_bin(stage).unwrap_or_else(|e| panic!("{stage}: {e}"))
}

/// The path of `stage`'s binary: its argv[0] when run by [`cmd`].
pub fn bin_path(stage: &str) -> PathBuf {
    assert_cmd::cargo::cargo_bin(stage)
}

/// The binary of `stage` as a `std::process::Command`, for tests that spawn it and act on the
/// running process (signals, pipes).
pub fn process(stage: &str) -> std::process::Command {
    std::process::Command::new(bin_path(stage))
}

/// `n` unit normals on a Fibonacci spiral (z uniform, golden-angle steps in φ), as f32.
pub fn spiral_normals(n: usize) -> Vec<[f32; 3]> {
    (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let (r, phi) = ((1.0 - z * z).sqrt(), i as f64 * 2.399_963_229_728_653);
            [(r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32]
        })
        .collect()
}

/// A lat-long image of `f(direction)` at the texel centres.
pub fn latlong(w: usize, h: usize, f: impl Fn(DVec3) -> [f32; 3]) -> RgbImage {
    let grid = prtkit::sphere::LatLong::new(w, h);
    RgbImage::from_fn(w, h, |x, y| f(grid.texel_direction(x, y)))
}

/// A sky with a sun (40× the sky at its peak, cos²⁰⁰ wide), a bright horizon band and a darker,
/// textured ground: every frequency present, and high dynamic range.
pub fn sky_image(w: usize, h: usize) -> RgbImage {
    let sun = DVec3::new(0.4, 0.3, 0.6).normalize();
    latlong(w, h, |d| {
        let s = 40.0 * d.dot(sun).max(0.0).powi(200);
        let sky = if d.z > 0.0 { 1.0 + 0.5 * (1.0 - d.z) } else { 0.3 + 0.1 * (3.0 * d.x).sin().abs() };
        [(sky + s) as f32, (sky * 0.9 + s) as f32, (sky * 0.8 + 0.9 * s) as f32]
    })
}

/// [`sky_image`] as a lat-long environment map.
pub fn sky(w: usize, h: usize) -> EnvMap {
    EnvMap::latlong(sky_image(w, h)).expect("a 2:1 image is a lat-long map")
}

/// Writes `image` as `dir/name` in PFM.
pub fn write_pfm(dir: &Path, name: &str, image: &RgbImage) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, pfm::encode(image)).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    path
}

/// Writes `image` as `dir/name` in OpenEXR.
pub fn write_exr(dir: &Path, name: &str, image: &RgbImage) -> PathBuf {
    let path = dir.join(name);
    let bytes = prtkit::io::exr::encode_layers(&[("", image)]).unwrap_or_else(|e| panic!("{e}"));
    std::fs::write(&path, bytes).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    path
}

/// The sky at `w`×`h` written as `dir/sky.pfm`.
pub fn sky_pfm(dir: &Path, w: usize, h: usize) -> PathBuf {
    write_pfm(dir, "sky.pfm", &sky_image(w, h))
}

/// The prefilter → render chain: an SHRM baked by `prefilter` and the `render` that reads it.
pub struct Chain {
    /// The environment map both read.
    pub env: PathBuf,
    /// The BRDF spec both are given.
    pub brdf: String,
    /// The `prtkit.shrm` document (beside it, its EXR).
    pub document: PathBuf,
}

impl Chain {
    /// Runs `prefilter ENV --brdf BRDF ARGS -q --shrm dir/NAME.exr -o dir/NAME.json`, which must
    /// succeed.
    pub fn prefilter(dir: &Path, env: &Path, brdf: &str, name: &str, args: &[&str]) -> Chain {
        let document = dir.join(format!("{name}.json"));
        cmd("prefilter")
            .arg(env)
            .args(["--brdf", brdf, "-q"])
            .args(args)
            .arg("--shrm")
            .arg(dir.join(format!("{name}.exr")))
            .arg("-o")
            .arg(&document)
            .assert()
            .success();
        Chain { env: env.to_path_buf(), brdf: brdf.to_string(), document }
    }

    /// `render ENV --shading shrm --brdf BRDF --shrm DOCUMENT -q`, for the caller to complete.
    pub fn render(&self) -> Command {
        let mut render = cmd("render");
        render.arg(&self.env).args(["--shading", "shrm", "--brdf", &self.brdf, "-q", "--shrm"]).arg(&self.document);
        render
    }
}

/// Parses JSON output into a library type, showing the text when it does not fit.
pub fn parse<T: DeserializeOwned>(bytes: &[u8]) -> T {
    serde_json::from_slice(bytes)
        .unwrap_or_else(|e| panic!("{e} in {} JSON: {}", std::any::type_name::<T>(), String::from_utf8_lossy(bytes)))
}

/// Reads a JSON file into a library type.
pub fn read<T: DeserializeOwned>(path: &Path) -> T {
    parse(&std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())))
}

/// A command's stderr as text.
pub fn stderr(output: &std::process::Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

/// Runs `STAGE ARGS -q` in `dir`, which must succeed.
pub fn run_in(dir: &Path, stage: &str, args: &[&str]) {
    let out = cmd(stage).args(args).arg("-q").current_dir(dir).output().unwrap();
    assert!(out.status.success(), "{stage} {args:?}: {}", stderr(&out));
}

/// `render ARGS -q --json` in `dir`, which must succeed: its relative RMS error against
/// `--compare` (NaN when the run reports none, which fails any bound).
pub fn render_rel_error(dir: &Path, args: &[&str]) -> f64 {
    let out = cmd("render").args(args).args(["-q", "--json"]).current_dir(dir).output().unwrap();
    assert!(out.status.success(), "render {args:?}: {}", stderr(&out));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    v["metrics"]["rel_error"].as_f64().unwrap_or(f64::NAN)
}

/// The path of `testdata/meshes/NAME`, as a string for argument lists.
pub fn test_mesh(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("testdata/meshes").join(name).display().to_string()
}

/// The names of the entries of `dir`, sorted.
pub fn entries(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// The temporary files of unfinished outputs (`.prtkit-*.tmp`) under `dir`, recursively.
pub fn temporaries(dir: &Path) -> Vec<PathBuf> {
    let mut found = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap_or_default().to_string_lossy();
        if path.is_dir() {
            found.extend(temporaries(&path));
        } else if name.starts_with(".prtkit-") && name.ends_with(".tmp") {
            found.push(path);
        }
    }
    found
}

/// Copies the directory tree `from` to `to`, except the entries named in `skip` (at any depth).
pub fn copy_tree(from: &Path, to: &Path, skip: &[&str]) {
    std::fs::create_dir_all(to).unwrap_or_else(|e| panic!("{}: {e}", to.display()));
    for entry in std::fs::read_dir(from).unwrap_or_else(|e| panic!("{}: {e}", from.display())) {
        let entry = entry.unwrap();
        if skip.iter().any(|s| entry.file_name() == *s) {
            continue;
        }
        let (src, dst) = (entry.path(), to.join(entry.file_name()));
        if entry.file_type().unwrap().is_dir() {
            copy_tree(&src, &dst, skip);
        } else {
            std::fs::copy(&src, &dst).unwrap_or_else(|e| panic!("{}: {e}", src.display()));
        }
    }
}

/// The directory of the stages' binaries (the ones these tests run).
pub fn bin_dir() -> PathBuf {
    bin_path("prtkit").parent().expect("a binary is in a directory").to_owned()
}

/// `PATH` with the stages' binaries first, for scripts that call them by name.
pub fn path_with_stages() -> std::ffi::OsString {
    let rest = std::env::var_os("PATH").unwrap_or_default();
    std::env::join_paths(std::iter::once(bin_dir()).chain(std::env::split_paths(&rest))).expect("PATH entries")
}

/// Parses `src` as a GLSL 450 fragment shader with naga's front end and validates the module
/// (every flag, every capability), failing with `what`, the error and the source.
pub fn check_glsl_fragment(src: &str, what: &str) {
    let module = naga::front::glsl::Frontend::default()
        .parse(&naga::front::glsl::Options::from(naga::ShaderStage::Fragment), src)
        .unwrap_or_else(|e| panic!("{what}: {e:?}\n{src}"));
    validate_naga(&module, what);
}

/// Parses `src` as WGSL with naga's front end and validates the module, failing with `what`,
/// the error in context and the source.
pub fn check_wgsl(src: &str, what: &str) {
    let module =
        naga::front::wgsl::parse_str(src).unwrap_or_else(|e| panic!("{what}: {}\n{src}", e.emit_to_string(src)));
    validate_naga(&module, what);
}

/// naga's validator over `module`, every flag and capability.
fn validate_naga(module: &naga::Module, what: &str) {
    naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all())
        .validate(module)
        .unwrap_or_else(|e| panic!("{what}: {e:?}"));
}
