//! Every input is read within its ceiling (`docs/limits.md`, issue 34): files, devices and
//! standard input alike, through the one reader `prtkit::io::read_bytes`. One test per kind of
//! input, each fed `/dev/zero` (as a path and on stdin) and a file one byte over its ceiling
//! (sparse, so the test writes almost nothing). Every run is made under an address-space limit
//! (`prlimit --as`): the ceilings follow it (a quarter of it for files read whole, an eighth for
//! documents), and a reader that did not stop at its ceiling would fail to allocate and abort
//! (exit 134) instead of exiting 2 with the message asserted here.

mod common;

use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// The address-space limit of every run: 1 GiB.
const ADDRESS_SPACE: u64 = 1 << 30;
/// Files read whole (images, normals, meshes, KTX2): ¼ of the memory the process may use.
const FILE_CEILING: u64 = ADDRESS_SPACE / 4;
/// JSON documents and manifests: ¼ of the memory budget (½ of the memory).
const DOCUMENT_CEILING: u64 = ADDRESS_SPACE / 8;
/// Shader sources: a fixed 1 MiB.
const SHADER_CEILING: u64 = 1 << 20;

/// Whether the ceilings above hold here: `prlimit` exists and the machine (and its cgroup) has
/// more memory than the limit, so that the limit is what sets the ceilings.
fn limited_runs_possible() -> bool {
    let ok = Path::new("/usr/bin/prlimit").exists() && prtkit::limits::available_memory() > ADDRESS_SPACE;
    if !ok {
        eprintln!("skipped: needs /usr/bin/prlimit and more than 1 GiB of memory");
    }
    ok
}

/// Runs `stage` under the address-space limit in `dir`; returns its exit code and stderr.
/// `stdin`: the file standard input reads (none: closed).
fn run_limited(dir: &Path, stage: &str, args: &[&str], stdin: Option<&Path>) -> (Option<i32>, String) {
    let stdin = match stdin {
        None => Stdio::null(),
        Some(path) => File::open(path).unwrap().into(),
    };
    let out = Command::new("/usr/bin/prlimit")
        .arg(format!("--as={ADDRESS_SPACE}"))
        .arg(common::bin_path(stage))
        .args(args)
        .current_dir(dir)
        .stdin(stdin)
        .output()
        .unwrap();
    (out.status.code(), common::stderr(&out))
}

/// A sparse file of `len` bytes starting with `start`: a file over a ceiling that costs nothing
/// to write.
fn sparse(dir: &Path, name: &str, start: &[u8], len: u64) -> PathBuf {
    let path = dir.join(name);
    let mut file = File::create(&path).unwrap();
    file.write_all(start).unwrap();
    file.set_len(len).unwrap();
    path
}

fn ceiling_words(ceiling: u64) -> String {
    format!("above the ceiling of {}", prtkit::limits::human_bytes(ceiling as u128))
}

/// A run: its arguments, its stdin and what its message must say (the input's name first).
type Case<'a> = (Vec<&'a str>, Option<&'a Path>, Vec<&'a str>);

/// Asserts that every run exits 2 with a message saying all it must, writing nothing.
fn refused(stage: &str, runs: &[Case]) {
    for (args, stdin, says) in runs {
        let dir = tempfile::tempdir().unwrap();
        let (code, stderr) = run_limited(dir.path(), stage, args, *stdin);
        assert_eq!(code, Some(2), "{stage} {args:?}: {stderr}");
        assert!(says.iter().all(|s| stderr.contains(s)), "{stage} {args:?}: expected {says:?}: {stderr}");
        assert!(common::entries(dir.path()).is_empty(), "{stage} {args:?} wrote {:?}", common::entries(dir.path()));
    }
}

const ZERO: &str = "/dev/zero";

#[test]
fn environment_maps_from_a_file_a_device_or_stdin_stop_at_the_file_ceiling() {
    if !limited_runs_possible() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let big = sparse(dir.path(), "big.pfm", b"PF\n", FILE_CEILING + 1);
    let big = big.to_str().unwrap();
    let over = ceiling_words(FILE_CEILING);
    refused(
        "sh-project",
        &[
            (vec![big, "-o", "d.json"], None, vec!["big.pfm", &over]),
            (vec!["-", "-o", "d.json"], Some(Path::new(big)), vec!["<stdin>", &over]),
            (vec!["-", "-o", "d.json"], Some(Path::new(ZERO)), vec!["<stdin>", "does not start like an EXR"]),
        ],
    );
}

#[test]
fn sh_documents_from_a_file_a_device_or_stdin_stop_at_the_document_ceiling() {
    if !limited_runs_possible() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let big = sparse(dir.path(), "big.sh.json", b"{", DOCUMENT_CEILING + 1);
    let big = big.to_str().unwrap();
    let over = ceiling_words(DOCUMENT_CEILING);
    let args = |sh| vec!["--sh", sh, "--brdf", "lambert", "-o", "d.json"];
    refused(
        "prefilter",
        &[
            (args(big), None, vec!["big.sh.json", &over]),
            (args("-"), Some(Path::new(big)), vec!["<stdin>", &over]),
            (args(ZERO), None, vec![ZERO, "does not start with '{'"]),
            (args("-"), Some(Path::new(ZERO)), vec!["<stdin>", "does not start with '{'"]),
        ],
    );
}

#[test]
fn shader_sources_from_a_file_a_device_or_stdin_stop_at_one_mebibyte() {
    if !limited_runs_possible() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let big = sparse(dir.path(), "big.sl", b"// ", SHADER_CEILING + 1);
    let big = big.to_str().unwrap();
    let over = ceiling_words(SHADER_CEILING);
    let args = |sl| vec![sl, "--res", "8x8", "-o", "t.exr"];
    refused(
        "sample-shader",
        &[
            (args(big), None, vec!["big.sl", &over]),
            (args(ZERO), None, vec![ZERO, &over]),
            (args("-"), Some(Path::new(ZERO)), vec!["<stdin>", &over]),
        ],
    );
}

#[test]
fn normals_codes_and_reports_stop_at_their_ceilings() {
    if !limited_runs_possible() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let big = sparse(dir.path(), "big.f32", b"", FILE_CEILING + 1);
    let big = big.to_str().unwrap();
    let over = ceiling_words(FILE_CEILING);
    let codes = dir.path().join("codes.bin");
    std::fs::write(&codes, [0u8; 8]).unwrap();
    let codes = codes.to_str().unwrap();
    refused(
        "encode-normals",
        &[
            // Normals to encode (raw f32 triples).
            (vec![big, "-o", "c.bin"], None, vec!["big.f32", &over]),
            (vec![ZERO, "-o", "c.bin"], None, vec![ZERO, &over]),
            (vec!["-", "-o", "c.bin"], Some(Path::new(ZERO)), vec!["<stdin>", &over]),
            // Codes to decode.
            (vec!["--decode", big, "-o", "n.f32"], None, vec!["big.f32", &over]),
            (vec!["--decode", "-", "-o", "n.f32"], Some(Path::new(ZERO)), vec!["<stdin>", &over]),
            // The report a decode reads its layout from: a JSON document.
            (vec!["--decode", codes, "--header", ZERO, "-o", "n.f32"], None, vec![ZERO, "does not start with '{'"]),
        ],
    );
}

#[test]
fn manifests_meshes_and_merl_files_stop_at_their_ceilings() {
    if !limited_runs_possible() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let sky = common::sky_pfm(dir.path(), 16, 8);
    let sky = sky.to_str().unwrap();
    let big = sparse(dir.path(), "big.manifest", b"# ", DOCUMENT_CEILING + 1);
    let big = big.to_str().unwrap();
    let document = ceiling_words(DOCUMENT_CEILING);
    refused(
        "count-terms",
        &[
            (vec!["--manifest", big, "--plot", "k.svg"], None, vec!["big.manifest", &document]),
            (vec!["--manifest", "-", "--plot", "k.svg"], Some(Path::new(ZERO)), vec!["<stdin>", &document]),
        ],
    );
    refused(
        "render",
        &[(vec![sky, "--scene", ZERO, "--res", "8x8", "-o", "r.exr"], None, vec![ZERO, &ceiling_words(FILE_CEILING)])],
    );
    // A MERL file has one size, which is its ceiling.
    let merl = ceiling_words(prtkit::brdf::merl::FILE_BYTES as u64);
    refused("factor-brdf", &[(vec!["merl:/dev/zero", "-o", "d.json"], None, vec![ZERO, &merl])]);
}

#[test]
fn ktx2_files_an_ibl_manifest_names_are_read_within_the_file_ceiling() {
    if !limited_runs_possible() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let sky = common::sky_pfm(dir.path(), 32, 16);
    let bake = dir.path().join("bake");
    common::cmd("ibl").arg(&sky).arg("-o").arg(&bake).args(["--size", "8", "--min-size", "4", "-q"]).assert().success();
    let manifest = bake.join("ibl.json");
    let text = std::fs::read_to_string(&manifest).unwrap();
    let render = |manifest: &Path| {
        vec![
            sky.to_str().unwrap().to_string(),
            "--shading".into(),
            "ibl".into(),
            "--ibl".into(),
            manifest.to_str().unwrap().to_string(),
            "--brdf".into(),
            "gltf".into(),
            "--res".into(),
            "8x8".into(),
            "-o".into(),
            "r.exr".into(),
        ]
    };
    // The specular file named as a device: refused after its first bytes.
    let device = dir.path().join("device.json");
    std::fs::write(&device, text.replace("\"specular.ktx2\"", "\"/dev/zero\"")).unwrap();
    assert_ne!(std::fs::read_to_string(&device).unwrap(), text, "the manifest names specular.ktx2");
    // A specular file one byte over the ceiling, starting like a KTX2 file.
    sparse(&bake, "specular.ktx2", &prtkit::io::ktx2::IDENTIFIER, FILE_CEILING + 1);
    let (device_args, big_args) = (render(&device), render(&manifest));
    let over = ceiling_words(FILE_CEILING);
    refused(
        "render",
        &[
            (device_args.iter().map(String::as_str).collect(), None, vec!["device.json", ZERO, "KTX 2.0 identifier"]),
            (big_args.iter().map(String::as_str).collect(), None, vec!["ibl.json", "specular.ktx2", &over]),
        ],
    );
}

#[test]
fn gltf_assets_and_their_buffers_are_read_within_the_file_ceiling() {
    if !limited_runs_possible() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let big = sparse(d, "big.glb", b"glTF", FILE_CEILING + 1);
    sparse(d, "big.bin", b"", FILE_CEILING + 1);
    std::os::unix::fs::symlink(ZERO, d.join("zero.glb")).unwrap();
    std::os::unix::fs::symlink(ZERO, d.join("zero.bin")).unwrap();
    // Assets whose one buffer is a file over the ceiling, a device, or claims more than it.
    let asset = |name: &str, bytes: u64, uri: &str| {
        let text =
            format!(r#"{{"asset": {{"version": "2.0"}}, "buffers": [{{"byteLength": {bytes}, "uri": "{uri}"}}]}}"#);
        std::fs::write(d.join(name), text).unwrap();
        d.join(name).to_str().unwrap().to_string()
    };
    let (far, device, claims) = (
        asset("far.gltf", 42, "big.bin"),
        asset("device.gltf", 42, "zero.bin"),
        asset("claims.gltf", 1 << 40, "big.bin"),
    );
    let zero_glb = d.join("zero.glb");
    let over = ceiling_words(FILE_CEILING);
    let args = |mesh: &str| vec![mesh.to_string(), "--glb".into(), "t.glb".into(), "-o".into(), "t.json".into()];
    let runs = [
        (args(big.to_str().unwrap()), vec!["big.glb", over.as_str()]),
        (args(zero_glb.to_str().unwrap()), vec!["zero.glb", "does not start like glTF"]),
        (args(&far), vec!["far.gltf: buffer 0", "big.bin", &over]),
        (args(&device), vec!["device.gltf: buffer 0", "zero.bin", &over]),
        (args(&claims), vec!["claims.gltf", "the buffers' byteLength together is 1.0 TiB", &over]),
    ];
    let runs: Vec<Case> =
        runs.iter().map(|(a, says)| (a.iter().map(String::as_str).collect(), None, says.clone())).collect();
    refused("transfer", &runs);
}

/// `ibl` plans its memory before it allocates any (`ibl::stage::Config::planned_bytes`): under
/// a 1 GiB address space (a 512 MiB budget) 2048² faces are refused at once with the figure they
/// need, where they used to abort in the encoder; 1024² faces bake.
#[test]
fn ibl_refuses_up_front_a_bake_its_memory_cannot_hold() {
    if !limited_runs_possible() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let mut pfm = b"PF\n64 32\n-1.0\n".to_vec();
    for k in 0..64 * 32 * 3 {
        pfm.extend_from_slice(&(0.5 + (k % 7) as f32 * 0.1).to_le_bytes());
    }
    std::fs::write(dir.path().join("sky.pfm"), pfm).unwrap();
    let (code, stderr) = run_limited(dir.path(), "ibl", &["sky.pfm", "-o", "big", "--size", "2048", "-q"], None);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(
        stderr.contains("the memory the bake needs is") && stderr.contains("above the ceiling of 512.0 MiB"),
        "{stderr}"
    );
    assert!(!dir.path().join("big").exists());
    let (code, stderr) = run_limited(dir.path(), "ibl", &["sky.pfm", "-o", "fits", "--size", "1024", "-q"], None);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(dir.path().join("fits/specular.ktx2").is_file());
}
