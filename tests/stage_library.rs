//! Each stage's library entry point and its binary, run on the same input, give the same bytes
//! for every output. The config is built here as the command line builds it, with `args` the
//! argv the binary is given (argv[0] included); outputs are encoded with the library's writers.
//! The `--json` summaries agree except their timings. Also: every example in `examples/` runs.

mod common;

use common::{bin_path, cmd, parse, Chain};
use glam::DVec3;
use prtkit::brdf::Brdf;
use prtkit::envmap::{EnvMap, Layout, LoadOptions};
use prtkit::io::document::to_json_pretty;
use prtkit::io::image::encode_image;
use prtkit::io::{exr, Document, RgbImage};
use prtkit::progress::NoProgress;
use std::path::{Path, PathBuf};

/// A directory with the sky (64×32 PFM) the runs read, and where the binary writes.
struct Bench {
    _dir: tempfile::TempDir,
    root: PathBuf,
    sky: String,
}

fn bench() -> Bench {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().to_path_buf();
    let sky = common::sky_pfm(&root, 64, 32).to_str().unwrap().to_string();
    Bench { _dir: dir, root, sky }
}

impl Bench {
    /// Runs `stage ARGS` in the bench directory (must succeed) and returns the argv it was given
    /// and its stdout.
    fn binary(&self, stage: &str, args: &[&str]) -> (Vec<String>, Vec<u8>) {
        let out = cmd(stage).args(args).current_dir(&self.root).output().unwrap();
        assert!(out.status.success(), "{stage} {args:?}: {}", common::stderr(&out));
        let argv = std::iter::once(bin_path(stage).to_str().unwrap().to_string())
            .chain(args.iter().map(|a| a.to_string()))
            .collect();
        (argv, out.stdout)
    }

    /// The bytes the binary wrote to `name`.
    fn file(&self, name: &str) -> Vec<u8> {
        std::fs::read(self.root.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
    }

    /// The sky read the way every stage reads an environment map.
    fn env(&self) -> EnvMap {
        LoadOptions::default().load(Path::new(&self.sky)).unwrap().map
    }

    /// Asserts the library's bytes for `name` are the binary's.
    fn same(&self, name: &str, library: &[u8]) {
        assert!(self.file(name) == library, "{name}: the library's bytes differ from the binary's");
    }

    fn same_image(&self, name: &str, image: &RgbImage, exposure: f32) {
        self.same(name, &encode_image(Path::new(name), image, exposure).unwrap());
    }

    fn same_layers(&self, name: &str, layers: &[(String, RgbImage)]) {
        let refs: Vec<(&str, &RgbImage)> = layers.iter().map(|(n, i)| (n.as_str(), i)).collect();
        self.same(name, &exr::encode_layers(&refs).unwrap());
    }
}

/// A summary as JSON with the named timing fields (at any depth) removed.
fn untimed<T: serde::Serialize>(summary: &T, timings: &[&str]) -> serde_json::Value {
    fn strip(v: &mut serde_json::Value, keys: &[&str]) {
        match v {
            serde_json::Value::Object(map) => {
                map.retain(|k, _| !keys.contains(&k.as_str()));
                map.values_mut().for_each(|v| strip(v, keys));
            }
            serde_json::Value::Array(items) => items.iter_mut().for_each(|v| strip(v, keys)),
            _ => {}
        }
    }
    let mut v = serde_json::to_value(summary).unwrap();
    strip(&mut v, timings);
    v
}

#[test]
fn convert_library_and_binary_write_the_same_bytes() {
    use prtkit::envmap::stage::{run, Config};
    let b = bench();
    b.binary("convert", &[&b.sky, "--to", "cross-horizontal", "--supersample", "2", "-o", "cross.exr"]);
    let config = Config { to: Layout::CrossHorizontal, size: None, supersample: 2 };
    b.same_image("cross.exr", run(&config, &b.env()).unwrap().image(), 0.0);

    b.binary("convert", &[&b.sky, "--to", "faces", "--size", "8x8", "--face-format", "png", "-o", "faces"]);
    let config = Config { to: Layout::Faces, size: Some((8, 8)), supersample: 3 };
    let faces = run(&config, &b.env()).unwrap();
    for (face, image) in prtkit::envmap::FACES.iter().zip(faces.images()) {
        b.same_image(&format!("faces/{}.png", face.short_name()), image, 0.0);
    }
}

#[test]
fn sh_project_library_and_binary_write_the_same_bytes() {
    use prtkit::limits::MAX_EPSILON_ORDER;
    use prtkit::sh::project::OrderChoice;
    use prtkit::sh::stage::{run, Config, Summary};
    let b = bench();
    let args = [&b.sky, "-e", "0.05", "-o", "sky.sh.json", "--reconstruct", "r.exr", "--irradiance", "e.png", "--json"];
    let (argv, stdout) = b.binary("sh-project", &args);
    let config = Config {
        order: OrderChoice::Epsilon { epsilon: 0.05, max_search: MAX_EPSILON_ORDER },
        reconstruction: true,
        irradiance: true,
        size: None,
        window: prtkit::sh::window::Window::Lanczos,
        irradiance_window: prtkit::sh::window::Window::Nonneg,
        source: b.sky.clone(),
        args: argv,
    };
    let out = run(&config, &b.env(), &NoProgress).unwrap();
    b.same("sky.sh.json", to_json_pretty(&out.document).as_bytes());
    b.same_image("r.exr", out.reconstruction.as_ref().unwrap(), 0.0);
    b.same_image("e.png", out.irradiance.as_ref().unwrap(), 0.0);
    let printed: Summary = parse(&stdout);
    assert_eq!(untimed(&printed, &["project_seconds"]), untimed(&out.summary, &["project_seconds"]));
}

#[test]
fn prefilter_library_and_binary_write_the_same_bytes() {
    use prtkit::prefilter::pipeline::Lighting;
    use prtkit::prefilter::stage::{run, Config, MapRequest, Summary};
    let b = bench();
    let brdf = "torrance-sparrow:sigma=0.3";
    let args = [&b.sky, "--brdf", brdf, "--no-cosine", "-e", "0.05", "--max-p", "3", "--size", "32x16", "--bound"];
    let outputs = ["--shrm", "s.exr", "--view", "0,0.3,1", "--reflection-map", "v.exr", "--kautz-mccool", "k.exr"];
    let rest = ["--slices", "3", "-o", "s.json", "--json"];
    let (argv, stdout) = b.binary("prefilter", &[&args[..], &outputs, &rest].concat());
    let config = Config {
        cosine: false,
        epsilon: 0.05,
        max_p: 3,
        bound: true,
        size: Some((32, 16)),
        shrm_file: Some("s.exr".into()),
        maps: vec![MapRequest { file: "v.exr".into(), view: DVec3::new(0.0, 0.3, 1.0).normalize() }],
        kautz_mccool_slices: 3,
        source: b.sky.clone(),
        args: argv,
        ..Config::new(Brdf::parse(brdf).unwrap())
    };
    let env = b.env();
    let out = run(&config, Lighting::Map(&env), &NoProgress).unwrap();
    b.same("s.json", to_json_pretty(&out.document).as_bytes());
    b.same_layers("s.exr", out.shrm_layers.as_ref().unwrap());
    b.same_layers("k.exr", out.kautz_mccool.as_ref().unwrap());
    b.same_image("v.exr", &out.maps[0], 0.0);
    let printed: Summary = parse(&stdout);
    assert_eq!(untimed(&printed, &["timings"]), untimed(&out.summary, &["timings"]));

    // From a prtkit.sh document, irradiance of a Lambertian surface, on a cube cross.
    b.binary("sh-project", &[&b.sky, "-F", "4", "-o", "sky.sh.json"]);
    let sh = "sky.sh.json";
    let args = ["--sh", sh, "--brdf", "lambert", "--irradiance", "e.pfm", "--output-layout", "cross-vertical"];
    let (argv, _) = b.binary("prefilter", &[&args[..], &["-o", "l.json"]].concat());
    let doc = prtkit::sh::document::parse(&String::from_utf8(b.file(sh)).unwrap()).unwrap();
    let config = Config {
        irradiance: true,
        output_layout: Layout::CrossVertical,
        source: sh.into(),
        args: argv,
        ..Config::new(Brdf::parse("lambert").unwrap())
    };
    let out = run(&config, Lighting::Coefficients(&doc.body.coeffs()), &NoProgress).unwrap();
    b.same("l.json", to_json_pretty(&out.document).as_bytes());
    b.same_image("e.pfm", out.irradiance.as_ref().unwrap(), 0.0);
}

#[test]
fn factor_brdf_library_and_binary_write_the_same_bytes() {
    use prtkit::factor::stage::{run, Config, Summary};
    use prtkit::factor::{Channel, Domain, Method, Sampling};
    let b = bench();
    let args = ["phong:s=8", "--resolution", "12", "--cosine", "--terms", "4", "--factors", "f.exr", "--maps", "maps"];
    let (argv, stdout) = b.binary("factor-brdf", &[&args[..], &["-o", "f.json", "--json"]].concat());
    let config = Config {
        sampling: Sampling { resolution: 12, domain: Domain::Hemisphere, cosine: true, channel: Channel::Luminance },
        method: Method::Auto,
        terms: 4,
        maps: true,
        maps_dir: Some("maps".into()),
        factors_file: Some("f.exr".into()),
        max_memory: 4 << 30,
        args: argv,
    };
    let out = run(&config, &Brdf::parse("phong:s=8").unwrap(), &NoProgress).unwrap();
    b.same("f.json", to_json_pretty(&out.document).as_bytes());
    let f = out.factors.as_ref().unwrap();
    b.same("f.exr", &exr::encode_grey_layers(f.width, f.height, &[("g", &f.g), ("h", &f.h)]).unwrap());
    let (layers, sheet) = out.maps.as_ref().unwrap();
    b.same_layers("maps/factors.exr", layers);
    b.same_image("maps/factors.png", sheet, 0.0);
    let printed: Summary = parse(&stdout);
    assert_eq!(printed, out.summary);
}

#[test]
fn count_terms_library_and_binary_write_the_same_bytes() {
    use prtkit::factor::count::{markdown_table, run, CountConfig, Material};
    use prtkit::factor::{plot, Channel, Domain, Sampling};
    let b = bench();
    let specs = ["phong:s=8", "torrance-sparrow:sigma=0.3"];
    let args = ["--brdf", specs[0], "--brdf", specs[1], "--resolution", "16", "--max-terms", "30", "--plot", "k.svg"];
    let (_, table) = b.binary("count-terms", &args);
    let (_, json) =
        b.binary("count-terms", &[&args[..4], &["--resolution", "16", "--max-terms", "30", "--json"]].concat());
    let config = CountConfig::new(Sampling {
        resolution: 16,
        domain: Domain::Hemisphere,
        cosine: false,
        channel: Channel::Luminance,
    });
    let materials = specs
        .iter()
        .map(|s| {
            // Named by its canonical spec, as the command line names a --brdf.
            let brdf = Brdf::parse(s).unwrap();
            Material { name: brdf.spec(), brdf, channel: Channel::Luminance, budget: Some(30) }
        })
        .collect();
    let out = run(&config, materials, &NoProgress).unwrap();
    assert_eq!(String::from_utf8(table).unwrap(), markdown_table(&out.rows));
    assert_eq!(String::from_utf8(json).unwrap(), to_json_pretty(&out.rows));
    // The plot's title is composed by the command line.
    let title = "count-terms: hemisphere , n = 16, 99.0 % energy";
    b.same("k.svg", plot::count_plot(title, &out.rows, &out.spectra).unwrap().as_bytes());
}

#[test]
fn encode_normals_library_and_binary_write_the_same_bytes() {
    use prtkit::normals::pack::Stream;
    use prtkit::normals::sources::raw_to_bytes;
    use prtkit::normals::{encode, InvalidPolicy, Scheme};
    let b = bench();
    // A Fibonacci spiral of 500 directions, the axes and one zero-length normal (replaced).
    let mut normals = common::spiral_normals(500);
    normals.extend([[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, 0.0]]);
    std::fs::write(b.root.join("n.f32"), raw_to_bytes(&normals)).unwrap();
    let args = ["n.f32", "--scheme", "cm", "--bits", "20", "--packed", "--on-invalid", "replace", "--bins", "8"];
    let outputs = ["-o", "codes.bin", "--report", "r.json", "--decoded", "d.f32"];
    let (argv, _) = b.binary("encode-normals", &[&args[..], &outputs[..]].concat());
    let config = encode::Config {
        scheme: Scheme::Cm,
        bits: 20,
        stream: Stream::Packed,
        on_invalid: InvalidPolicy::Replace,
        histogram_bins: 8,
        files: encode::Files::new(Path::new("n.f32"), Some("codes.bin".into()), Some("d.f32".into())),
        args: argv,
    };
    let out = encode::run(&config, &normals, &NoProgress).unwrap();
    b.same("codes.bin", &out.stream);
    b.same("r.json", out.report.to_json().as_bytes());
    b.same("d.f32", &raw_to_bytes(&out.decoded));
}

#[test]
fn sample_shader_library_and_binary_write_the_same_bytes() {
    use prtkit::shader::sampler::{Arith, Domain};
    use prtkit::shader::stage::{run, Config, Stats};
    use prtkit::shader::Shader;
    let b = bench();
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("testdata/shaders/marble.sl");
    let file = file.to_str().unwrap();
    let args = [file, "--res", "32x32", "--tolerance", "0.05", "--verify", "8", "-p", "veining=4", "-o", "t.exr"];
    let (argv, stdout) = b.binary("sample-shader", &[&args[..], &["--stats", "s.json", "--json", "-q"]].concat());
    let config = Config {
        tolerance: 0.05,
        max_depth: None,
        resolution: (32, 32),
        domain: Domain::Texture,
        arithmetics: vec![Arith::Affine],
        points_per_node: 8,
        seed: 1,
        verify: Some(8),
        repeat: 1,
        file: file.into(),
        args: argv,
    };
    let mut shader = Shader::compile(&std::fs::read_to_string(file).unwrap(), file).unwrap();
    shader.set_params(&[("veining".into(), "4".into())]).unwrap();
    let out = run(&config, &shader, &NoProgress).unwrap();
    assert_eq!(out.violations, 0);
    b.same("s.json", to_json_pretty(&out.stats[0]).as_bytes());
    let layers = [("", &out.texture), ("width", &out.width), ("depth", &out.depth)];
    b.same("t.exr", &exr::encode_layers(&layers).unwrap());
    // `--json`: the statistics with the sampling time (the library's `seconds`).
    let mut printed: Document<Stats> = parse(&stdout);
    assert!(printed.body.seconds.is_some_and(|s| s >= 0.0) && out.seconds.len() == 1);
    printed.body.seconds = None;
    assert_eq!(printed, out.stats[0]);
}

#[test]
fn render_library_and_binary_write_the_same_bytes() {
    use prtkit::render::stage::{run, Config, PanelItem, Shading, StoredFactors, Summary};
    use prtkit::render::{Camera, Scene};
    let b = bench();
    let camera = || Camera::look_at(DVec3::new(0.0, -4.0, 0.0), DVec3::ZERO, 32.0, 24, 24).unwrap();
    // The reference, then the prefilter → render chain compared with it, with every output.
    b.binary("render", &[&b.sky, "--brdf", "phong:s=8", "--res", "24x24", "-o", "ref.exr"]);
    let chain = Chain::prefilter(&b.root, Path::new(&b.sky), "phong:s=8", "p8", &["--order", "8,0"]);
    let doc = chain.document.to_str().unwrap();
    let args = [&b.sky, "--shading", "shrm", "--brdf", "phong:s=8", "--shrm", doc, "--res", "24x24", "-o", "r.exr"];
    let outputs = ["--png", "r.png", "--exposure", "-1", "--compare", "ref.exr", "--error-image", "e.exr"];
    let more = ["--metrics", "m.json", "--panel", "p.png", "--panel-item", "reference=ref.exr", "--json"];
    let (argv, stdout) = b.binary("render", &[&args[..], &outputs, &more].concat());
    let reference = prtkit::io::image::read_image(&b.root.join("ref.exr")).unwrap();
    let (shrm, body) = prtkit::render::reflection::load(&chain.document).unwrap();
    let config = Config {
        brdf: Brdf::parse("phong:s=8").unwrap(),
        shading: Shading::Shrm { shrm, body: Box::new(body), window: prtkit::sh::window::Window::Nonneg },
        camera: camera(),
        env_rotation: 0.0,
        compare: Some(("ref.exr".into(), reference.clone())),
        panel: Some(vec![PanelItem { label: "reference".into(), image: Some(reference) }]),
        label: None,
        exposure: -1.0,
        output_name: Some("r.exr".into()),
        args: argv,
    };
    let out = run(&config, &b.env(), &Scene::unit_sphere(), &NoProgress).unwrap();
    b.same_image("r.exr", &out.frame.image, -1.0);
    b.same_image("r.png", &out.frame.image, -1.0);
    let (metrics, error_image) = out.comparison.as_ref().unwrap();
    b.same_image("e.exr", error_image, -1.0);
    b.same("m.json", to_json_pretty(metrics).as_bytes());
    b.same_image("p.png", out.panel.as_ref().unwrap(), -1.0);
    let printed: Summary = parse(&stdout);
    assert_eq!(untimed(&printed, &["seconds"]), untimed(&out.summary, &["seconds"]));

    // A factorization stored by factor-brdf, relit.
    b.binary(
        "factor-brdf",
        &["phong:s=8", "--resolution", "16", "--cosine", "--terms", "6", "--factors", "f.exr", "-o", "f.json"],
    );
    let args = [&b.sky, "--shading", "factored", "--brdf", "phong:s=8", "--factors", "f.json", "-K", "6"];
    b.binary("render", &[&args[..], &["--res", "24x24", "--normal-table", "32x16", "-o", "k.exr"]].concat());
    let (body, factorization) = prtkit::factor::document::load(&b.root.join("f.json")).unwrap();
    let factors = StoredFactors { name: "f.json".into(), factorization, cosine: body.cosine, brdf: body.brdf };
    let config = Config {
        shading: Shading::Factored {
            terms: 6,
            factors: Some(Box::new(factors)),
            resolution: None,
            cell_samples: 2,
            normal_table: (32, 16),
            bright: prtkit::envmap::bright::BrightRule::Auto,
        },
        compare: None,
        panel: None,
        exposure: 0.0,
        output_name: Some("k.exr".into()),
        args: Vec::new(),
        ..config
    };
    let out = run(&config, &b.env(), &Scene::unit_sphere(), &NoProgress).unwrap();
    b.same_image("k.exr", &out.frame.image, 0.0);
}

#[test]
fn ibl_library_and_binary_write_the_same_bytes() {
    use prtkit::ibl::stage::{run, Config};
    let b = bench();
    let (argv, _) = b.binary("ibl", &[&b.sky, "-o", "bake", "--size", "32", "--samples", "16", "-q"]);
    let config = Config { size: 32, samples: 16, source: b.sky.clone(), args: argv, ..Config::default() };
    let out = run(&config, &b.env(), &NoProgress).unwrap();
    let mut files = vec![
        (prtkit::ibl::manifest::FILE.to_string(), out.document.to_json().into_bytes()),
        (out.document.body.sh.file.clone(), out.sh_document.to_json().into_bytes()),
    ];
    files.extend(
        out.textures()
            .map(|(name, texture, format)| (name.to_string(), out.container.encode(&texture, format).unwrap())),
    );
    files.extend(out.shaders().map(|(name, text)| (name.to_string(), text.into_bytes())));
    assert_eq!(common::entries(&b.root.join("bake")).len(), files.len());
    for (name, bytes) in &files {
        b.same(&format!("bake/{name}"), bytes);
    }
}

// ---------------------------------------------------------------------------------------------
// The examples: each stage through the library alone, reproducing the README's commands.

// The examples, compiled into this test (their `main`s unused here).
#[allow(dead_code)]
#[path = "../examples/convert.rs"]
mod convert_example;
#[allow(dead_code)]
#[path = "../examples/count_terms.rs"]
mod count_terms_example;
#[allow(dead_code)]
#[path = "../examples/encode_normals.rs"]
mod encode_normals_example;
#[allow(dead_code)]
#[path = "../examples/factor_brdf.rs"]
mod factor_brdf_example;
#[allow(dead_code)]
#[path = "../examples/ibl.rs"]
mod ibl_example;
#[allow(dead_code)]
#[path = "../examples/prefilter.rs"]
mod prefilter_example;
#[allow(dead_code)]
#[path = "../examples/render.rs"]
mod render_example;
#[allow(dead_code)]
#[path = "../examples/sample_shader.rs"]
mod sample_shader_example;
#[allow(dead_code)]
#[path = "../examples/sh_project.rs"]
mod sh_project_example;

#[test]
fn every_example_runs_and_writes_what_it_documents() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path();
    // In the README's order: the sky first, then what reads it.
    sample_shader_example::run(out).unwrap();
    convert_example::run(out).unwrap();
    sh_project_example::run(out).unwrap();
    prefilter_example::run(out).unwrap();
    count_terms_example::run(out).unwrap();
    factor_brdf_example::run(out).unwrap();
    render_example::run(out).unwrap();
    ibl_example::run(out).unwrap();
    encode_normals_example::run(out).unwrap();
    for file in [
        "sky.exr",
        "sky-cross.exr",
        "sky.sh.json",
        "sky-irr.png",
        "phong32.png",
        "p30.json",
        "p30.exr",
        "ref.exr",
        "k75.png",
        "sphere.codes",
        "sphere.normals.json",
        "sphere-decoded.obj",
        "table32.md",
        "ibl/ibl.json",
        "ibl/specular.ktx2",
    ] {
        assert!(out.join(file).is_file(), "no {file} among {:?}", common::entries(out));
    }
    let doc: prtkit::io::Document<prtkit::sh::document::ShBody> = common::read(&out.join("sky.sh.json"));
    assert!(doc.body.selection.epsilon_achieved_clipped.is_some_and(|e| e <= 0.1), "{:?}", doc.body.selection);
    let doc: prtkit::io::Document<prtkit::factor::document::FactorBody> = common::read(&out.join("p30.json"));
    assert_eq!(doc.body.factors.map(|f| f.terms), Some(75));
    let doc = prtkit::normals::report::read(&out.join("sphere.normals.json")).unwrap();
    assert!(doc.body.count > 0 && doc.body.error.max <= doc.body.bound * 1.0001, "{:?}", doc.body.error);
}
