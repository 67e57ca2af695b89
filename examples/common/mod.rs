//! What the measuring examples share.

use std::path::PathBuf;

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
