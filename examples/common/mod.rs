//! What the measuring examples share: the shared light probes, as paths and (for the ring-free
//! tables) as 256×128 lat-long maps, and the angular references those tables are measured
//! against, cached on disk (they take most of the time).

// Each example compiles this module on its own and uses a part of it.
#![allow(dead_code)]

use anyhow::Context;
use glam::DVec3;
use prtkit::brdf::Brdf;
use prtkit::envmap::bright::BrightRule;
use prtkit::envmap::{resample, EnvMap, Layout, LoadOptions};
use prtkit::io::image::{read_image, write_image};
use prtkit::io::RgbImage;
use prtkit::prefilter::pipeline::Lighting;
use prtkit::prefilter::stage::{self, Config, MapRequest, Method};
use prtkit::progress::NoProgress;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The shared light probes (`../shared/testdata/envmaps`, SOURCES.md there): the directory and
/// each probe's path in it (a cube's six faces are a directory), or `None` when it is absent.
pub fn shared_probes() -> Option<(PathBuf, Vec<String>)> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/testdata/envmaps");
    if !dir.is_dir() {
        eprintln!("skipping: {} is absent", dir.display());
        return None;
    }
    let names = ["grace_latlong.exr", "grace128.hdr", "grace_probe_250.pfm", "uffizi_ict_latlong_256x128.hdr"]
        .map(String::from)
        .into_iter()
        .chain(["grace", "rnl", "stpeters", "galileo"].map(|probe| format!("dxsdk_cubes/{probe}/")))
        .collect();
    Some((dir, names))
}

/// The size every probe is resampled to, and every map baked at.
pub const SIZE: (usize, usize) = (256, 128);

/// The grazing view of the tables: 11° above the horizon of +X.
pub fn grazing() -> DVec3 {
    DVec3::new(1.0, 0.0, 0.2).normalize()
}

/// The probe (a map file or a cube-face directory) as a 256×128 lat-long map.
pub fn probe_map(path: &Path) -> anyhow::Result<EnvMap> {
    let map = LoadOptions::default().load(path).with_context(|| format!("cannot read {}", path.display()))?.map;
    Ok(resample(&map, Layout::LatLong, SIZE.0, SIZE.1, 4)?)
}

/// The probe's name in tables and cache files: the file stem, "(cube)" for face directories.
pub fn probe_name(path: &str) -> String {
    let path = Path::new(path.trim_end_matches('/'));
    let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    match path.parent().and_then(|p| p.file_name()) {
        Some(parent) if parent == "dxsdk_cubes" => format!("{stem} (cube)"),
        _ => stem,
    }
}

/// The cache suffix of the ε = 0.001 reference (`--method angular`'s default settings). It
/// changes when that reference does, so that no cache serves an older one: "-bands" since the
/// reference sums the map in luminance bands.
pub const LOOSE: &str = "-bands";

/// The cache file of a reference: `{probe}-{brdf}-{view}{suffix}.exr` in `cache`.
pub fn reference_file(cache: &str, probe: &str, spec: &str, view: &str, suffix: &str) -> PathBuf {
    Path::new(cache).join(format!("{probe}-{spec}-{view}{suffix}.exr"))
}

/// The angular reference (`--method angular`) at `epsilon` for `view`, read from `file` when
/// it is there, else computed and written to it.
pub fn reference(
    map: &EnvMap,
    brdf: &Brdf,
    view: DVec3,
    epsilon: f64,
    bright: BrightRule,
    file: &Path,
) -> anyhow::Result<RgbImage> {
    if let Ok(image) = read_image(file) {
        return Ok(image);
    }
    let config = Config {
        method: Method::Angular,
        epsilon,
        bright,
        size: Some(SIZE),
        maps: vec![MapRequest { file: file.display().to_string(), view }],
        ..Config::new(brdf.clone())
    };
    let image = stage::run(&config, Lighting::Map(map), &NoProgress)?.maps.remove(0);
    write_image(file, &image, 0.0)?;
    Ok(image)
}

/// One `prefilter` bake of the reflection map for `view` at 256×128, the configuration as
/// `setup` makes it from the defaults: the stage's output and the library call's wall-clock
/// seconds.
pub fn bake(
    map: &EnvMap,
    brdf: &Brdf,
    view: DVec3,
    setup: impl FnOnce(Config) -> Config,
) -> anyhow::Result<(stage::Output, f64)> {
    let config = setup(Config {
        size: Some(SIZE),
        maps: vec![MapRequest { file: "map.exr".into(), view }],
        ..Config::new(brdf.clone())
    });
    // In the worker pool, as the CLI runs its stage (`pool.install`): from the main thread
    // every parallel region of the bake would hop threads, a wake-up and a sleep each (tens of
    // µs on a shared machine), which a user's run does not pay.
    let start = Instant::now();
    let out = rayon::scope(|_| stage::run(&config, Lighting::Map(map), &NoProgress))?;
    Ok((out, start.elapsed().as_secs_f64()))
}
