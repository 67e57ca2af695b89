//! The fuzz targets: for each parser, a corpus of real inputs, a mutator, the library entry
//! point and the binary that reads that kind of file.

use crate::mutate::{self, Rng};
use glam::DVec3;
use prtkit::io::RgbImage;
use std::path::{Path, PathBuf};

/// What a target does with one input file.
pub struct Target {
    /// Parser name; also the folder under `testdata/bad/`.
    pub name: &'static str,
    /// Extension of the input files.
    pub ext: &'static str,
    /// Mutates an input (`other` is another corpus input, for splicing).
    pub mutate: fn(&mut Rng, &[u8], &[u8]) -> Vec<u8>,
    /// Runs the library on the file: `Err(message)` is a (good) error.
    pub library: fn(&Path) -> Result<(), String>,
    /// The binary and its arguments for the file; outputs go to `out`, the corpus is in `work`.
    pub binary: fn(&Path, &Path, &Path) -> (&'static str, Vec<String>),
    /// Whether an error message must name the input file (a spec string is not a file).
    pub names_file: bool,
}

fn s(p: &Path) -> String {
    p.display().to_string()
}

fn err<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

fn read_image(p: &Path) -> Result<(), String> {
    prtkit::io::image::read_image(p).map(drop).map_err(err)
}

fn image_binary(file: &Path, out: &Path, _: &Path) -> (&'static str, Vec<String>) {
    ("sh-project", vec![s(file), "--order".into(), "2".into(), "-o".into(), s(&out.join("s.json")), "-q".into()])
}

fn render(work: &Path, out: &Path, extra: &[String]) -> Vec<String> {
    let mut v =
        vec![s(&work.join("sky.exr")), "--res".into(), "8x8".into(), "-o".into(), s(&out.join("r.exr")), "-q".into()];
    v.extend_from_slice(extra);
    v
}

/// Every target.
pub fn all() -> Vec<Target> {
    vec![
        Target {
            name: "exr",
            ext: "exr",
            mutate: mutate::exr,
            library: |p| {
                read_image(p)?;
                prtkit::io::exr::read_layers(p).map(drop).map_err(err)
            },
            binary: image_binary,
            names_file: true,
        },
        Target {
            name: "hdr",
            ext: "hdr",
            mutate: |rng, d, o| mutate::header_number(rng, d, 4, o),
            library: read_image,
            binary: image_binary,
            names_file: true,
        },
        Target {
            name: "pfm",
            ext: "pfm",
            mutate: |rng, d, o| mutate::header_number(rng, d, 3, o),
            library: read_image,
            binary: image_binary,
            names_file: true,
        },
        Target {
            name: "merl",
            ext: "binary",
            mutate: |rng, d, _| mutate::merl(rng, d),
            library: |p| {
                let m = prtkit::brdf::merl::MerlBrdf::read(p).map_err(err)?;
                m.eval(DVec3::Z, DVec3::new(0.6, 0.0, 0.8));
                Ok(())
            },
            binary: |file, out, _| {
                let spec = format!("merl:{}", file.display());
                (
                    "factor-brdf",
                    vec![spec, "--resolution".into(), "4".into(), "-o".into(), s(&out.join("f.json")), "-q".into()],
                )
            },
            names_file: true,
        },
        Target {
            name: "sh",
            ext: "sh.json",
            mutate: mutate::json,
            library: |p| {
                let doc = prtkit::sh::document::read(p).map_err(err)?;
                doc.body.coeffs().band_energy();
                Ok(())
            },
            binary: |file, out, work| {
                ("render", render(work, out, &["--shading".into(), "irradiance".into(), "--sh".into(), s(file)]))
            },
            names_file: true,
        },
        Target {
            name: "shrm",
            ext: "shrm.json",
            mutate: mutate::json,
            library: |p| {
                let (shrm, body) = prtkit::render::reflection::load(p).map_err(err)?;
                prtkit::render::reflection::ShrmShader::new(shrm, body.parameterization == "normal", DVec3::Z);
                Ok(())
            },
            binary: |file, out, work| {
                let args = ["--shading", "shrm", "--brdf", "phong:s=8", "--shrm"].map(String::from);
                let mut a = args.to_vec();
                a.push(s(file));
                ("render", render(work, out, &a))
            },
            names_file: true,
        },
        Target {
            name: "factor",
            ext: "factor.json",
            mutate: mutate::json,
            library: |p| prtkit::factor::document::load(p).map(drop).map_err(err),
            binary: |file, out, work| {
                let args = ["--shading", "factored", "--brdf", "phong:s=8", "--factors"].map(String::from);
                let mut a = args.to_vec();
                a.push(s(file));
                ("render", render(work, out, &a))
            },
            names_file: true,
        },
        Target {
            name: "shader",
            ext: "sl",
            mutate: mutate::shader,
            library: |p| {
                use prtkit::affine::{Affine, Interval};
                use prtkit::shader::sampler::{globals, point_value, Domain};
                let src = prtkit::shader::read_source(p).map_err(err)?;
                let shader = prtkit::shader::Shader::compile(&src, &s(p)).map_err(err)?;
                let domain = if shader.uses_direction() { Domain::LatLong } else { Domain::Texture };
                point_value(&shader, domain, 0.3, 0.6, 0.01, 0.01).map_err(err)?;
                shader.eval(&globals::<Interval>(domain, [0.0, 1.0], [0.0, 1.0])).map_err(err)?;
                shader.eval(&globals::<Affine>(domain, [0.25, 0.5], [0.5, 0.75])).map_err(err)?;
                Ok(())
            },
            binary: |file, out, _| {
                (
                    "sample-shader",
                    vec![s(file), "--res".into(), "8x8".into(), "-o".into(), s(&out.join("s.exr")), "-q".into()],
                )
            },
            names_file: true,
        },
        Target {
            name: "brdf",
            ext: "spec",
            mutate: mutate::brdf_spec,
            library: |p| {
                let text = std::fs::read_to_string(p).map_err(err)?;
                // MERL files are the merl target's; a mutated path is read by no one.
                if text.trim_start().to_ascii_lowercase().starts_with("merl") {
                    return Ok(());
                }
                let brdf = prtkit::brdf::Brdf::parse(&text).map_err(err)?;
                for (wi, wo) in [(DVec3::Z, DVec3::Z), (DVec3::new(0.6, 0.0, 0.8), DVec3::new(-0.6, 0.0, 0.8))] {
                    let v = brdf.eval(wi, wo);
                    // Within the peak ceiling, values are finite: an infinity is a finding.
                    if v.iter().any(|x| !x.is_finite()) {
                        panic!("BRDF {text:?} evaluates to {v:?}");
                    }
                }
                Ok(())
            },
            binary: |file, out, _| {
                // A command-line argument cannot hold a NUL byte.
                let spec = String::from_utf8_lossy(&std::fs::read(file).unwrap_or_default()).replace('\0', "");
                (
                    "factor-brdf",
                    vec![spec, "--resolution".into(), "4".into(), "-o".into(), s(&out.join("f.json")), "-q".into()],
                )
            },
            names_file: false,
        },
        Target {
            name: "obj",
            ext: "obj",
            mutate: mutate::lines,
            library: |p| {
                let mesh = prtkit::mesh::Mesh::load(p).map(drop).map_err(err);
                let normals = prtkit::normals::sources::NormalSource::read(p, false).map(drop).map_err(err);
                mesh.and(normals)
            },
            binary: |file, out, work| ("render", render(work, out, &["--scene".into(), s(file)])),
            names_file: true,
        },
        Target {
            name: "ply",
            ext: "ply",
            mutate: |rng, d, o| mutate::header_number(rng, d, 8, o),
            library: |p| {
                // Both PLY readers: the normals' (encode-normals) and the mesh's (render, transfer).
                let mesh = prtkit::mesh::Mesh::load(p).map(drop).map_err(err);
                let normals = prtkit::normals::sources::NormalSource::read(p, false).map(drop).map_err(err);
                normals.and(mesh)
            },
            binary: |file, out, _| ("encode-normals", vec![s(file), "-o".into(), s(&out.join("c.bin")), "-q".into()]),
            names_file: true,
        },
        Target {
            name: "gltf",
            ext: "gltf",
            mutate: mutate::json,
            library: |p| prtkit::mesh::Mesh::load(p).map(drop).map_err(err),
            binary: |file, out, work| ("render", render(work, out, &["--scene".into(), s(file)])),
            names_file: true,
        },
        Target {
            name: "glb",
            ext: "glb",
            mutate: mutate::glb,
            library: |p| prtkit::mesh::Mesh::load(p).map(drop).map_err(err),
            binary: |file, out, _| {
                let args = ["--mode", "unshadowed", "-q", "--glb"].map(String::from);
                (
                    "transfer",
                    [vec![s(file)], args.to_vec(), vec![s(&out.join("t.glb")), "-o".into(), s(&out.join("t.json"))]]
                        .concat(),
                )
            },
            names_file: true,
        },
        Target {
            name: "manifest",
            ext: "txt",
            mutate: mutate::lines,
            library: |p| prtkit::factor::manifest::read(p).map(drop).map_err(err),
            binary: |file, _, _| {
                (
                    "count-terms",
                    vec!["--manifest".into(), s(file), "--predict-only".into(), "--resolution".into(), "4".into()],
                )
            },
            names_file: true,
        },
        Target {
            name: "ktx2",
            ext: "ktx2",
            mutate: mutate::ktx2,
            library: |p| {
                let ceiling = prtkit::limits::max_file_bytes();
                let bytes =
                    prtkit::io::read_bytes(p, "KTX2", ceiling, prtkit::io::ktx2::check_identifier).map_err(err)?;
                prtkit::io::ktx2::decode(&bytes).map(drop).map_err(|e| format!("{}: {e}", p.display()))
            },
            // Rendered as the specular cube of the corpus bake: a manifest beside the input names it.
            binary: |file, out, work| {
                let text = std::fs::read_to_string(work.join("ibl.json")).unwrap_or_default();
                let name = file.file_name().unwrap_or_default().to_string_lossy().to_string();
                let manifest = file.with_extension("ibl.json");
                std::fs::write(&manifest, text.replace("\"specular.ktx2\"", &format!("{name:?}")))
                    .unwrap_or_else(|e| panic!("{e}"));
                ("render", render(work, out, &ibl_args(&manifest)))
            },
            names_file: true,
        },
        Target {
            name: "ibl",
            ext: "ibl.json",
            mutate: mutate::json,
            library: |p| prtkit::render::ibl::IblBake::load(p).map(drop).map_err(err),
            binary: |file, out, work| ("render", render(work, out, &ibl_args(file))),
            names_file: true,
        },
    ]
}

/// `render` arguments that shade with the bake of `manifest`.
fn ibl_args(manifest: &Path) -> Vec<String> {
    let mut args = ["--shading", "ibl", "--brdf", "gltf:roughness=0.5", "--ibl"].map(String::from).to_vec();
    args.push(s(manifest));
    args
}

/// The binary's path (built by cargo for integration tests).
pub fn binary_path(name: &str) -> PathBuf {
    match name {
        "sh-project" => env!("CARGO_BIN_EXE_sh-project"),
        "render" => env!("CARGO_BIN_EXE_render"),
        "factor-brdf" => env!("CARGO_BIN_EXE_factor-brdf"),
        "sample-shader" => env!("CARGO_BIN_EXE_sample-shader"),
        "encode-normals" => env!("CARGO_BIN_EXE_encode-normals"),
        "count-terms" => env!("CARGO_BIN_EXE_count-terms"),
        "prefilter" => env!("CARGO_BIN_EXE_prefilter"),
        "ibl" => env!("CARGO_BIN_EXE_ibl"),
        "transfer" => env!("CARGO_BIN_EXE_transfer"),
        other => panic!("no binary {other}"),
    }
    .into()
}

/// Radiance RGBE bytes of `img`: flat pixels, or new-style run-length scanlines.
fn rgbe(img: &RgbImage, rle: bool) -> Vec<u8> {
    let mut out = format!("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\nEXPOSURE=1.0\n\n-Y {} +X {}\n", img.height, img.width)
        .into_bytes();
    let encode = |p: [f32; 3]| -> [u8; 4] {
        let m = p[0].max(p[1]).max(p[2]) as f64;
        if m < 1e-32 {
            return [0; 4];
        }
        let e = m.log2().floor() as i32 + 1;
        let f = 256.0 / 2f64.powi(e);
        [(p[0] as f64 * f) as u8, (p[1] as f64 * f) as u8, (p[2] as f64 * f) as u8, (e + 128) as u8]
    };
    for y in 0..img.height {
        let row: Vec<[u8; 4]> = img.row(y).iter().map(|p| encode(*p)).collect();
        if rle {
            out.extend_from_slice(&[2, 2, (img.width >> 8) as u8, img.width as u8]);
            for c in 0..4 {
                for chunk in row.chunks(128) {
                    out.push(chunk.len() as u8);
                    out.extend(chunk.iter().map(|p| p[c]));
                }
            }
        } else {
            out.extend(row.iter().flatten());
        }
    }
    out
}

/// A MERL file whose three channels are smooth functions of the bin index.
fn merl_bytes() -> Vec<u8> {
    use prtkit::brdf::merl::{CHANNEL_LEN, FILE_BYTES};
    let mut b = Vec::with_capacity(FILE_BYTES);
    for d in [90i32, 90, 180] {
        b.extend_from_slice(&d.to_le_bytes());
    }
    for c in 0..3 {
        for i in 0..CHANNEL_LEN {
            b.extend_from_slice(&((i % 977) as f64 * (c + 1) as f64).to_le_bytes());
        }
    }
    b
}

fn run_ok(bin: &str, args: &[&str], dir: &Path) {
    let out = std::process::Command::new(binary_path(bin))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap_or_else(|e| panic!("{bin}: {e}"));
    assert!(out.status.success(), "{bin} {args:?}: {}", String::from_utf8_lossy(&out.stderr));
}

/// A document as prtkit wrote it, with the parts that change from run to run (provenance
/// paths, timings) fixed, so that a seed always makes the same inputs.
fn document(p: &Path) -> Vec<u8> {
    let text = std::fs::read(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    let mut v: serde_json::Value = serde_json::from_slice(&text).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    v["provenance"] = serde_json::json!({"tool": "prtkit", "stage": "fuzz", "args": [], "inputs": []});
    if v.get("timings").is_some() {
        v["timings"] = serde_json::json!({});
    }
    serde_json::to_vec_pretty(&v).unwrap_or_default()
}

/// Builds the corpus in `work`: `(target name, seed inputs)`. Documents are made by the
/// binaries themselves (so they are what prtkit writes), beside the EXR files they name.
pub fn corpus(work: &Path) -> Vec<(&'static str, Vec<Vec<u8>>)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let shaders = root.join("testdata/shaders");
    let sky = shaders.join("sky.sl");
    let sky = sky.to_str().unwrap_or_default();
    run_ok("sample-shader", &[sky, "--latlong", "32x16", "--tolerance", "0.05", "-o", "sky.exr", "-q"], work);
    run_ok("sh-project", &["sky.exr", "--order", "3", "-o", "sky.sh.json", "-q"], work);
    run_ok(
        "prefilter",
        &["sky.exr", "--brdf", "phong:s=8", "--order", "3", "--shrm", "p.shrm.exr", "-o", "p.shrm.json", "-q"],
        work,
    );
    run_ok(
        "factor-brdf",
        &["phong:s=8", "--resolution", "6", "--factors", "f.exr", "--terms", "12", "-o", "f.factor.json", "-q"],
        work,
    );
    // A small bake of the same sky, its files beside the corpus (where documents find them).
    run_ok("ibl", &["sky.exr", "--size", "8", "--min-size", "4", "--samples", "0", "-o", "bake", "-q"], work);
    for file in ["ibl.json", "specular.ktx2", "irradiance.ktx2", "dfg.ktx2"] {
        std::fs::copy(work.join("bake").join(file), work.join(file)).unwrap_or_else(|e| panic!("{file}: {e}"));
    }
    let read = |p: &Path| std::fs::read(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    let img = RgbImage::from_fn(16, 8, |x, y| [x as f32 * 0.5 + 0.1, y as f32 * 0.25, 2.0]);
    let small = RgbImage::from_fn(4, 2, |x, y| [x as f32, y as f32, 0.5]);
    let grey = prtkit::io::exr::encode_grey_layers(4, 4, &[("", &[0.5f32; 16])]).unwrap_or_default();
    let layered = prtkit::io::exr::encode_layers(&[("", &img), ("coef.3", &img)]).unwrap_or_default();
    let shared = root.join("../shared/testdata/envmaps/grace128.hdr");
    let mut hdr = vec![rgbe(&img, false), rgbe(&RgbImage::from_fn(40, 3, |x, _| [x as f32, 1.0, 0.5]), true)];
    if shared.exists() {
        hdr.push(read(&shared));
    }
    let merl = merl_bytes();
    std::fs::write(work.join("synthetic.binary"), &merl).unwrap_or_else(|e| panic!("{e}"));
    let mut sl: Vec<PathBuf> =
        std::fs::read_dir(&shaders).map(|d| d.filter_map(|e| e.ok()).map(|e| e.path()).collect()).unwrap_or_default();
    sl.sort();
    let ply_header = |fmt: &str| {
        format!(
            "ply\nformat {fmt} 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
        )
    };
    let mut ply_bin = ply_header("binary_little_endian").into_bytes();
    for k in 0..3 {
        for v in [k as f32, (k == 1) as u8 as f32, (k == 2) as u8 as f32, 0.0, 0.6, 0.8] {
            ply_bin.extend(v.to_le_bytes());
        }
    }
    ply_bin.push(3);
    ply_bin.extend([0i32, 1, 2].iter().flat_map(|i| i.to_le_bytes()));
    vec![
        (
            "exr",
            vec![
                read(&work.join("sky.exr")),
                layered,
                grey,
                prtkit::io::exr::encode_layers(&[("", &small)]).unwrap_or_default(),
            ],
        ),
        ("hdr", hdr),
        ("pfm", vec![prtkit::io::pfm::encode(&img), prtkit::io::pfm::encode(&small)]),
        ("merl", vec![merl]),
        ("sh", vec![document(&work.join("sky.sh.json"))]),
        ("shrm", vec![document(&work.join("p.shrm.json"))]),
        ("factor", vec![document(&work.join("f.factor.json"))]),
        ("shader", sl.iter().map(|p| read(p)).collect()),
        (
            "brdf",
            ["phong:s=30", "lafortune:kd=0.1,lobe=-1/1/20", "torrance-sparrow:sigma=0.2", "kajiya-kay:s=8", "lambert"]
                .iter()
                .map(|s| s.as_bytes().to_vec())
                .collect(),
        ),
        (
            "obj",
            vec![
                read(&root.join("testdata/meshes/bowl.obj")),
                b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvn 0 0 1\nvn 1 0 0\nf 1//1 2//1 3//1\nf 1//2 2//2 4//2\n"
                    .to_vec(),
            ],
        ),
        (
            "ply",
            vec![
                ply_header("ascii")
                    .into_bytes()
                    .into_iter()
                    .chain(b"0 0 0 0 0 1\n1 1 0 1 0 0\n0 0 1 0 1 0\n3 0 1 2\n".iter().copied())
                    .collect(),
                ply_bin,
            ],
        ),
        ("gltf", vec![read(&root.join("testdata/meshes/tetrahedra.gltf"))]),
        ("glb", glb_seeds()),
        (
            "manifest",
            vec![
                b"# name spec budget\nglossy phong:s=30 80\n\"matte floor\" lambert -\n".to_vec(),
                b"paint merl:synthetic.binary 64\nwax lafortune:kd=0.2,lobe=-1/1/10\n".to_vec(),
            ],
        ),
        ("ktx2", ["specular.ktx2", "irradiance.ktx2", "dfg.ktx2"].iter().map(|f| read(&work.join(f))).collect()),
        ("ibl", vec![document(&work.join("ibl.json"))]),
    ]
}

/// `.glb` seeds: a tetrahedron as `transfer` writes one (`NORMAL` and a custom `_PRT_0`), and
/// with 16-bit indices in a strip, written here.
fn glb_seeds() -> Vec<Vec<u8>> {
    let positions = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let normal = prtkit::io::glb::Attribute {
        name: "NORMAL".into(),
        components: 3,
        values: prtkit::io::glb::Values::Float([0.0, 0.6, 0.8].repeat(4)),
    };
    let prt = prtkit::io::glb::Attribute {
        name: "_PRT_0".into(),
        components: 4,
        values: prtkit::io::glb::Values::Float(vec![0.5; 16]),
    };
    let mesh = prtkit::io::glb::GlbMesh {
        positions,
        attributes: vec![normal, prt],
        triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        generator: "fuzz".into(),
        extras: serde_json::json!({}),
        blobs: Vec::new(),
    };
    let written = prtkit::io::glb::encode(&mesh).unwrap_or_default();
    // The same vertices as a strip of u16 indices: the JSON edited, the BIN chunk extended.
    let mut json = prtkit::io::glb::json_chunk(&written).unwrap_or_default();
    let mut bin = prtkit::io::glb::bin_chunk(&written).unwrap_or_default().to_vec();
    let at = bin.len();
    bin.extend([0u16, 1, 2, 3, 0, 1].iter().flat_map(|i| i.to_le_bytes()));
    bin.resize(bin.len().next_multiple_of(4), 0);
    if let Some(views) = json["bufferViews"].as_array_mut() {
        views.push(serde_json::json!({"buffer": 0, "byteOffset": at, "byteLength": 12}));
    }
    json["accessors"][3] = serde_json::json!({"bufferView": 4, "componentType": 5123, "count": 6, "type": "SCALAR"});
    json["meshes"][0]["primitives"][0]["mode"] = serde_json::json!(5);
    json["buffers"][0]["byteLength"] = serde_json::json!(bin.len());
    vec![written, mutate::glb_container(&serde_json::to_vec(&json).unwrap_or_default(), &bin)]
}

/// Applies one to three mutations of a random seed input of `target`.
pub fn input(rng: &mut Rng, target: &Target, seeds: &[Vec<u8>]) -> Vec<u8> {
    let base = mutate::pick(rng, seeds).clone();
    let other = mutate::pick(rng, seeds).clone();
    let mut d = base;
    for _ in 0..1 + mutate::below(rng, 3) {
        d = (target.mutate)(rng, &d, &other);
    }
    d
}
