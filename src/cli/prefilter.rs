//! `prefilter`: frequency-space prefiltering and spherical harmonic reflection maps
//! (Ramamoorthi & Hanrahan 2002), or the angular reference with `--method angular`.

use super::common::{parse_size, parse_xyz, Execution, Outcome};
use super::envinput::EnvInput;
use crate::brdf::Brdf;
use crate::envmap::{self, EnvMap, Layout};
use crate::io::document::{to_json_pretty, Document, Provenance};
use crate::io::{self, exr, Output, RgbImage};
use crate::prefilter::document::{layer_name, Lighting as DocLighting, MapEntry, ShrmBody, FORMAT, VERSION};
use crate::prefilter::model::{residual_bound, Centre, Model};
use crate::prefilter::pipeline::{self, Lighting, Orders};
use crate::prefilter::shrm;
use crate::sh::{count, lm};
use anyhow::{bail, Context, Result};
use clap::{Parser, ValueEnum};
use glam::DVec3;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Frequency-space (or angular) method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Method {
    /// Spherical-harmonic prefiltering (R&H 2002 App. C).
    Frequency,
    /// Direct integration over the environment per output texel, BRDF truncated at ε (App. D).
    Angular,
}

/// Prefilter an environment map with a BRDF: spherical harmonic reflection maps (SHRMs) and
/// reflection maps, orders of magnitude faster than angular integration.
#[derive(Debug, Parser)]
#[command(name = "prefilter", version, about, long_about)]
pub struct Args {
    /// Environment map (.exr/.hdr/.pfm or a face directory). Omit when giving --sh.
    #[arg(value_name = "ENVMAP", required_unless_present = "sh")]
    pub env: Option<PathBuf>,

    /// Layout of the environment map (detected by default).
    #[arg(long, value_parser = clap::value_parser!(Layout))]
    pub layout: Option<Layout>,

    /// Lighting as a `prtkit.sh` document from sh-project instead of a map (frequency method).
    #[arg(long, conflicts_with = "env")]
    pub sh: Option<PathBuf>,

    /// BRDF spec, e.g. phong:s=32, lambert, torrance-sparrow:sigma=0.2, merl:FILE (docs/brdf-specs.md).
    #[arg(long)]
    pub brdf: String,

    /// Tolerance: the smallest F_B, P_B keeping 1 - ε of the BRDF energy (§5.1). Also the angular
    /// method's truncation.
    #[arg(short = 'e', long, default_value_t = 0.01)]
    pub epsilon: f64,

    /// Fixed orders F_B[,P_B] instead of choosing them from ε.
    #[arg(long, value_parser = parse_orders)]
    pub order: Option<(usize, usize)>,

    /// Largest P_B the ε search considers.
    #[arg(long, default_value_t = 6)]
    pub max_p: usize,

    /// Use the model itself as ρ̂, without folding in max(N·ω_i, 0): the convention of R&H's
    /// microfacet (eq. 11) and Table 5. (Phong and Lambert always follow the paper's 1-D form.)
    #[arg(long)]
    pub no_cosine: bool,

    /// Report the conservative residual-energy bound of App. B in the JSON.
    #[arg(long)]
    pub bound: bool,

    /// Size WxH of the lat-long grid of reflection vectors (S_B). Default 2S x S with
    /// S = clamp(10·F_B, 32, 512) (§5.2: S ≈ 10F).
    #[arg(long, value_parser = parse_size)]
    pub size: Option<(usize, usize)>,

    /// Layout of the images written: latlong or cross-horizontal (resampled from lat-long).
    #[arg(long = "output-layout", default_value = "latlong", value_parser = clap::value_parser!(Layout))]
    pub output_layout: Layout,

    /// `prtkit.shrm` document (`-` for stdout, the default when --json is not given).
    #[arg(short, long)]
    pub output: Option<String>,

    /// Write the SHRM as one EXR with (P_B+1)² RGB layers named B<p><±q>.
    #[arg(long, value_name = "FILE.exr")]
    pub shrm: Option<PathBuf>,

    /// Store global coefficients (eq. 7–8) in --shrm instead of local ones (eq. 6).
    #[arg(long)]
    pub global: bool,

    /// View direction x,y,z (towards the viewer) for --reflection-map; repeatable, paired in order.
    #[arg(long, value_parser = parse_direction, allow_hyphen_values = true)]
    pub view: Vec<DVec3>,

    /// Reflection map for the matching --view (eq. 12): .exr, .pfm or .png; repeatable.
    #[arg(long, value_name = "FILE")]
    pub reflection_map: Vec<PathBuf>,

    /// Write Cabral's 12 icosahedral reflection maps ico00..ico11.exr into DIR.
    #[arg(long, value_name = "DIR")]
    pub icosahedral: Option<PathBuf>,

    /// Write a T x T grid of reflection maps view_<j>_<i>.exr into --views-dir.
    #[arg(long, value_name = "T", requires = "views_dir")]
    pub views: Option<usize>,

    /// Directory for --views.
    #[arg(long, value_name = "DIR")]
    pub views_dir: Option<PathBuf>,

    /// Kautz–McCool 3-D texture B(α, β, θ_o) from the q = 0 terms, one EXR layer per θ_o slice.
    #[arg(long, value_name = "FILE.exr")]
    pub kautz_mccool: Option<PathBuf>,

    /// Number of θ_o slices for --kautz-mccool.
    #[arg(long, default_value_t = 16)]
    pub slices: usize,

    /// Irradiance map E(N) for a lambert BRDF (the reflection map × π/albedo).
    #[arg(long, value_name = "FILE")]
    pub irradiance: Option<PathBuf>,

    /// frequency (default) or angular (the reference; reflection maps only).
    #[arg(long, value_enum, default_value_t = Method::Frequency)]
    pub method: Method,

    /// Negative pixels in the environment: error, clamp or keep.
    #[arg(long, value_enum, default_value_t = super::envinput::NegativePolicy::Error)]
    pub negative: super::envinput::NegativePolicy,

    /// Exposure in stops for PNG images.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub exposure: f32,

    /// Print a summary (orders, ε, timings) on stdout.
    #[arg(long)]
    pub json: bool,

    #[command(flatten)]
    pub run: Execution,
}

fn parse_orders(s: &str) -> Result<(usize, usize), String> {
    let mut parts = s.split(',');
    let f = parts.next().unwrap_or("").trim().parse().map_err(|_| format!("expected F or F,P, got {s:?}"))?;
    let p = match parts.next() {
        Some(p) => p.trim().parse().map_err(|_| format!("expected F or F,P, got {s:?}"))?,
        None => 0,
    };
    if parts.next().is_some() || f > 200 || p > 16 {
        return Err(format!("orders {s:?}: expected F,P with F <= 200 and P <= 16"));
    }
    Ok((f, p))
}

/// A view direction: `x,y,z`, non-zero, normalized.
fn parse_direction(s: &str) -> Result<DVec3, String> {
    let d = parse_xyz(s)?;
    if d.length() < 1e-12 {
        return Err("the view direction must be non-zero".into());
    }
    Ok(d.normalize())
}

/// Runs `prefilter`.
pub fn run(args: Args) -> Result<Outcome> {
    let bar = args.run.start()?;
    if !(args.epsilon > 0.0 && args.epsilon < 1.0) {
        bail!("--epsilon must be in (0, 1), got {}", args.epsilon);
    }
    if !args.reflection_map.is_empty() && args.reflection_map.len() != args.view.len() {
        // Radially symmetric BRDFs need no view; any view then gives the same map.
        if !args.view.is_empty() {
            bail!(
                "give one --view per --reflection-map ({} views, {} maps)",
                args.view.len(),
                args.reflection_map.len()
            );
        }
    }
    if !matches!(args.output_layout, Layout::LatLong | Layout::CrossHorizontal) {
        bail!("--output-layout must be latlong or cross-horizontal, got {}", args.output_layout);
    }
    let output = match (&args.output, args.json) {
        (Some(o), _) => Some(Output::parse(o)),
        (None, false) => Some(Output::Stdout),
        (None, true) => None,
    };
    if let Some(o) = &output {
        super::common::check_json_output(o, args.json)?;
    }
    if let Some(o) = &output {
        o.check_writable()?;
    }
    for p in args.reflection_map.iter().chain(&args.shrm).chain(&args.kautz_mccool).chain(&args.irradiance) {
        Output::File(p.clone()).check_writable()?;
    }

    let brdf = Brdf::parse(&args.brdf).with_context(|| format!("bad --brdf {:?}", args.brdf))?;
    let model = Model::new(brdf, !args.no_cosine)?;
    if args.irradiance.is_some() && model.centre() != Some(Centre::Normal) {
        bail!("--irradiance needs --brdf lambert (the irradiance map is Lambert's reflection map × π/albedo)");
    }
    let orders = match args.order {
        Some((f, p)) => Orders::Fixed { f, p },
        None => Orders::Epsilon { epsilon: args.epsilon, max_p: args.max_p },
    };

    // The lighting.
    let (env, sh_coeffs, source) = match (&args.env, &args.sh) {
        (Some(path), _) => {
            let input = EnvInput { path: path.clone(), layout: args.layout, negative: args.negative };
            (Some(input.load()?), None, path.display().to_string())
        }
        (None, Some(path)) => {
            let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
            let doc = crate::sh::document::parse(&text).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
            (None, Some(doc.body.coeffs()), path.display().to_string())
        }
        (None, None) => bail!("give an environment map or --sh FILE"),
    };

    let views = collect_views(&args, &model);
    let mut maps: Vec<(PathBuf, Option<DVec3>, RgbImage)> = Vec::new();
    let start = Instant::now();
    let (f_b, p_b, epsilon_achieved, timings, shrm_out, light_order, bound);
    let (width, height);
    match args.method {
        Method::Frequency => {
            let brdf_sh = pipeline::brdf_coefficients(&model, orders)?;
            let (w, h) = args.size.unwrap_or_else(|| default_size(brdf_sh.f));
            width = w;
            height = h;
            let lighting = match (&env, &sh_coeffs) {
                (Some(m), _) => Lighting::Map(m),
                (None, Some(c)) => Lighting::Coefficients(c),
                _ => bail!("no lighting"),
            };
            let fixed = Orders::Fixed { f: brdf_sh.f, p: brdf_sh.p };
            let result = pipeline::frequency(&model, lighting, fixed, width, height, &bar)
                .with_context(|| format!("cannot prefilter {source}"))?;
            let t = Instant::now();
            let global = shrm::to_global(&result.shrm);
            let dirs: Vec<DVec3> = views.iter().map(|(_, v)| v.unwrap_or(DVec3::Z)).collect();
            for ((path, view), image) in views.iter().zip(shrm::reflection_maps(&global, &dirs)) {
                maps.push((path.clone(), *view, image));
            }
            let maps_seconds = t.elapsed().as_secs_f64();
            f_b = result.brdf.f;
            p_b = result.brdf.p;
            epsilon_achieved = if matches!(orders, Orders::Epsilon { .. }) {
                result.brdf.residual(f_b, p_b)
            } else {
                // With fixed orders, measure against a generous expansion of the same BRDF.
                model.coefficients((2 * f_b).max(32), (p_b + 3).min(8)).residual(f_b, p_b)
            };
            light_order = result.lighting.order;
            bound = if args.bound { Some(app_b_bound(&result, env.as_ref())) } else { None };
            let mut t_json = serde_json::to_value(result.timings)?;
            t_json["maps_seconds"] = maps_seconds.into();
            t_json["total_seconds"] = start.elapsed().as_secs_f64().into();
            timings = t_json;
            shrm_out = Some(if args.global { global } else { result.shrm });
        }
        Method::Angular => {
            if args.shrm.is_some() || args.kautz_mccool.is_some() {
                bail!("--method angular writes reflection maps only (--reflection-map, --icosahedral, --views, --irradiance)");
            }
            let Some(env) = &env else { bail!("--method angular needs the environment map, not --sh") };
            let latlong = as_latlong(env)?;
            let brdf_sh = pipeline::brdf_coefficients(&model, orders)?;
            f_b = brdf_sh.f;
            p_b = brdf_sh.p;
            let (w, h) = args.size.unwrap_or_else(|| default_size(f_b));
            width = w;
            height = h;
            let dirs: Vec<DVec3> = views.iter().map(|(_, v)| v.unwrap_or(DVec3::Z)).collect();
            let t = Instant::now();
            let images = pipeline::angular_maps(&model, &latlong, &dirs, args.epsilon, width, height, &bar)?;
            let seconds = t.elapsed().as_secs_f64();
            if model.centre().is_some() {
                for (path, view) in &views {
                    maps.push((path.clone(), *view, images[0].clone()));
                }
            } else {
                for ((path, view), image) in views.iter().zip(images) {
                    maps.push((path.clone(), *view, image));
                }
            }
            epsilon_achieved = args.epsilon;
            light_order = 0;
            bound = None;
            timings = serde_json::json!({ "angular_seconds": seconds });
            shrm_out = None;
        }
    }

    // Write images.
    let layout = args.output_layout;
    let write = |path: &Path, image: &RgbImage| -> Result<()> {
        let image = to_output_layout(image, layout)?;
        io::image::write_image(path, &image, args.exposure)?;
        Ok(())
    };
    let mut entries = Vec::new();
    for (path, view, image) in &maps {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
        }
        write(path, image)?;
        entries.push(MapEntry { file: path.display().to_string(), view: view.map(|v| v.to_array()) });
    }
    if let Some(path) = &args.irradiance {
        // Lambert's map is radiance (albedo/π)·E(N); the irradiance is that × π/albedo. Any
        // written map will do (the model is view-independent), else the SHRM's one.
        let mut e = match (maps.first(), &shrm_out) {
            (Some(map), _) => map.2.clone(),
            (None, Some(shrm)) => shrm::reflection_map(shrm, DVec3::Z),
            (None, None) => bail!("no map to derive the irradiance from"),
        };
        let albedo = model.brdf().reflection_lobe(1.0).unwrap_or(1.0 / std::f64::consts::PI) * std::f64::consts::PI;
        let scale = (std::f64::consts::PI / albedo.max(1e-12)) as f32;
        e.pixels.iter_mut().for_each(|p| p.iter_mut().for_each(|c| *c *= scale));
        write(path, &e)?;
    }
    if let (Some(path), Some(s)) = (&args.kautz_mccool, &shrm_out) {
        let slices = shrm::kautz_mccool(s, args.slices.max(1));
        let converted: Vec<RgbImage> = slices.iter().map(|i| to_output_layout(i, layout)).collect::<Result<_>>()?;
        let names: Vec<String> = (0..converted.len()).map(|k| format!("theta{k:02}")).collect();
        let layers: Vec<(&str, &RgbImage)> = names.iter().map(|n| n.as_str()).zip(converted.iter()).collect();
        exr::write_layers(path, &layers)?;
    }
    let layer_names: Vec<String> = (0..count(p_b))
        .map(|i| {
            let (p, q) = lm(i);
            layer_name(p, q)
        })
        .collect();
    if let (Some(path), Some(s)) = (&args.shrm, &shrm_out) {
        let converted: Vec<RgbImage> = s.layers.iter().map(|i| to_output_layout(i, layout)).collect::<Result<_>>()?;
        let layers: Vec<(&str, &RgbImage)> = layer_names.iter().map(|n| n.as_str()).zip(converted.iter()).collect();
        exr::write_layers(path, &layers)?;
    }

    let body = ShrmBody {
        brdf: model.brdf().spec(),
        cosine: model.cosine(),
        method: match args.method {
            Method::Frequency => "frequency",
            Method::Angular => "angular",
        }
        .into(),
        f_b,
        p_b,
        epsilon: args.order.is_none().then_some(args.epsilon),
        epsilon_achieved,
        epsilon_bound: bound,
        parameterization: if model.centre() == Some(Centre::Normal) {
            "normal"
        } else if model.is_tangent() {
            "tangent"
        } else {
            "reflection"
        }
        .into(),
        layout: layout.name().into(),
        width,
        height,
        global: args.global,
        shrm_file: args.shrm.as_ref().map(|p| p.display().to_string()),
        layers: layer_names,
        lighting: DocLighting { source: source.clone(), order: light_order },
        maps: entries,
        timings: timings.clone(),
    };
    let doc = Document::new(FORMAT, VERSION, Provenance::current("prefilter", vec![source]), body);
    if let Some(o) = &output {
        o.write(doc.to_json().as_bytes()).with_context(|| format!("cannot write {}", o.display()))?;
    }
    if args.json {
        let summary = serde_json::json!({
            "brdf": doc.body.brdf, "method": doc.body.method, "f_b": f_b, "p_b": p_b,
            "epsilon_achieved": epsilon_achieved, "epsilon_bound": bound, "width": width, "height": height,
            "timings": timings,
        });
        Output::Stdout.write(to_json_pretty(&summary).as_bytes())?;
    }
    Ok(Outcome::Success)
}

fn default_size(f_b: usize) -> (usize, usize) {
    let s = (10 * f_b).clamp(32, 512).max(f_b + 1);
    (2 * s, s)
}

/// Views requested: explicit --view/--reflection-map pairs, the icosahedron, the T×T grid.
fn collect_views(args: &Args, model: &Model) -> Vec<(PathBuf, Option<DVec3>)> {
    let radial = model.centre().is_some();
    let tag = |v: DVec3| if radial { None } else { Some(v) };
    let mut out = Vec::new();
    for (i, path) in args.reflection_map.iter().enumerate() {
        out.push((path.clone(), tag(args.view.get(i).copied().unwrap_or(DVec3::Z))));
    }
    if let Some(dir) = &args.icosahedral {
        for (i, v) in shrm::icosahedron_views().into_iter().enumerate() {
            out.push((dir.join(format!("ico{i:02}.exr")), tag(v)));
        }
    }
    if let (Some(t), Some(dir)) = (args.views, &args.views_dir) {
        for (k, v) in shrm::view_grid(t).into_iter().enumerate() {
            out.push((dir.join(format!("view_{:02}_{:02}.exr", k / t, k % t)), tag(v)));
        }
    }
    out
}

fn as_latlong(env: &EnvMap) -> Result<EnvMap> {
    if env.layout() == Layout::LatLong {
        return Ok(env.clone());
    }
    let s = (env.max_order()).max(16);
    Ok(envmap::resample(env, Layout::LatLong, 2 * s, s, 3)?)
}

fn to_output_layout(image: &RgbImage, layout: Layout) -> Result<RgbImage> {
    if layout == Layout::LatLong {
        return Ok(image.clone());
    }
    let src = EnvMap::latlong(image.clone())?;
    let n = (image.height / 2).max(1);
    let out = envmap::resample(&src, layout, 4 * n, 3 * n, 2)?;
    Ok(out.image().clone())
}

/// App. B: ε_B ≤ B_res/(Σ|B|² + B_res) with B_res = Λ_{F+1}(ε_L L_tot)(ε_ρ ρ_tot).
fn app_b_bound(result: &pipeline::Frequency, env: Option<&EnvMap>) -> f64 {
    let f = result.brdf.f;
    let brdf_res = result.brdf.residual(f, result.brdf.p) * result.brdf.total_energy;
    let light_total =
        env.map(crate::sh::project::map_energy).unwrap_or_else(|| result.lighting.band_energy().iter().sum());
    let light_res = (light_total - result.lighting.band_energy().iter().sum::<f64>()).max(0.0);
    // Σ|B_lmpq|² with B_lmpq = Λ_l L_lm ρ̂_lpq (eq. 5), per channel.
    let mut captured = 0.0;
    for (i, lc) in result.lighting.rgb.iter().enumerate() {
        let (l, _) = lm(i);
        let lambda2 = crate::sh::convolve::lambda(l).powi(2);
        for p in 0..=result.brdf.p {
            for q in -(p.min(l) as isize)..=(p.min(l) as isize) {
                let r = result.brdf.get(l, p, q);
                captured += lambda2 * (0..3).map(|c| (lc[c] * r[c]).powi(2)).sum::<f64>();
            }
        }
    }
    residual_bound(f, light_res, brdf_res, captured)
}
