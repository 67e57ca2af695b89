//! `transfer`: clap arguments → [`transfer::stage::Config`] → one library call → outputs.
//!
//! [`transfer::stage::Config`]: crate::transfer::stage::Config

mod args;

use super::common::{Context, Outcome, Stage};
use super::options::{check_json_output, Execution};
use super::outputs::{check_outputs, Holds, Outputs};
use crate::io::Output;
use crate::limits::{
    MAX_CELL_SAMPLES, MAX_CPCA_CLUSTERS, MAX_CPCA_DIRECTIONS, MAX_CPCA_ROUND_WORK, MAX_TRANSFER_BOUNCES,
    MAX_TRANSFER_ORDER, MAX_TRANSFER_RAYS,
};
use crate::mesh::Mesh;
use crate::transfer::albedo::Albedo;
use crate::transfer::jobs::{read_part, Job};
use crate::transfer::lightmap::{LightmapConfig, LightmapUvs};
use crate::transfer::order;
use crate::transfer::stage::{self, Compression, Config, Error, GlossyConfig, Mode, DEFAULT_CELL_SAMPLES};
use anyhow::{Context as _, Result};
pub use args::*;

impl TryFrom<&Args> for Config {
    type Error = anyhow::Error;
    fn try_from(args: &Args) -> Result<Config> {
        if args.bounces.is_some() && args.mode != Mode::Interreflected {
            anyhow::bail!(
                "--bounces is for --mode interreflected (the mode is {})",
                format!("{:?}", args.mode).to_lowercase()
            );
        }
        let glb_name = match &args.glb {
            Some(Output::File(path)) => path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default(),
            Some(Output::Stdout) => "-".into(),
            None => String::new(),
        };
        let glossy = match &args.factors {
            Some(doc) => Some(glossy_config(args, doc)?),
            None => {
                if args.terms.is_some() || args.energy.is_some() || args.cell_samples.is_some() {
                    anyhow::bail!("-K, --energy and --cell-samples are for glossy transfer (--factors FACTOR.json)");
                }
                None
            }
        };
        let (order, order_reason) = match args.sh_energy {
            None => (args.order, None),
            Some(fraction) => {
                let chosen = order::for_energy(fraction, glossy.as_ref()).map_err(flagged)?;
                (chosen.order, Some(format!("{} (--sh-energy {fraction})", chosen.reason)))
            }
        };
        let compression = match (args.clusters, args.pca) {
            (Some(clusters), Some(components)) => Some(Compression { clusters, components }),
            _ => None,
        };
        let lightmap = lightmap_request(args)?.map(|(width, height, path, uvs)| LightmapConfig {
            width,
            height,
            file: path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default(),
            uvs,
        });
        Ok(Config {
            lightmap,
            glossy,
            compression,
            quantization: args.quantize,
            order,
            order_reason,
            mode: args.mode,
            rays: args.rays,
            bounces: args.bounces.unwrap_or(Config::default().bounces),
            seed: args.seed,
            albedo: args.albedo.clone(),
            offset: args.offset,
            source: args.mesh.display().to_string(),
            glb_name,
            args: std::env::args().collect(),
        })
    }
}

/// `--lightmap WxH FILE.exr` or `--texels WxH FILE.exr`: the grid's size, the file and where
/// the UVs come from.
fn lightmap_request(args: &Args) -> Result<Option<(usize, usize, std::path::PathBuf, LightmapUvs)>> {
    let (values, flag, uvs) = match (&args.lightmap, &args.texels) {
        (Some(v), _) => (v, "--lightmap", LightmapUvs::Mesh),
        (None, Some(v)) => (v, "--texels", LightmapUvs::Atlas),
        (None, None) => return Ok(None),
    };
    let [size, file] = values.as_slice() else { anyhow::bail!("{flag} takes WxH and FILE.exr") };
    let parsed = size
        .split_once(['x', 'X'])
        .and_then(|(w, h)| Some((w.trim().parse::<usize>().ok()?, h.trim().parse::<usize>().ok()?)));
    let Some((width, height)) = parsed else {
        anyhow::bail!("{flag} {size:?}: the size must be WxH, e.g. 256x256");
    };
    Ok(Some((width, height, std::path::PathBuf::from(file), uvs)))
}

/// Default energy fraction K must reach when -K is not given.
const DEFAULT_ENERGY: f64 = 0.99;

/// The glossy bake's factorization, read back from `factor-brdf`'s document, and its K.
fn glossy_config(args: &Args, doc: &std::path::Path) -> Result<GlossyConfig> {
    if args.terms.is_some() && args.energy.is_some() {
        anyhow::bail!("-K and --energy both choose the number of terms: give one");
    }
    let (body, factorization) = crate::factor::document::load(doc)?;
    let name = doc.display().to_string();
    let stored = factorization.g.len();
    let (terms, terms_reason) = match (args.terms, args.energy) {
        (Some(k), _) => (k, format!("-K {k}")),
        (None, energy) => {
            let fraction = energy.unwrap_or(DEFAULT_ENERGY);
            if !(fraction > 0.0 && fraction <= 1.0) {
                anyhow::bail!("--energy {fraction} must be in (0, 1]");
            }
            let want = factorization.terms_for(fraction);
            let k = want.min(stored);
            let reason = if want <= stored {
                format!("the fewest terms holding {:.4} of the BRDF matrix's energy (--energy)", fraction)
            } else {
                format!(
                    "{fraction} of the energy needs {want} terms; the factor file holds {stored} (factor-brdf --terms {want})"
                )
            };
            (k, reason)
        }
    };
    Ok(GlossyConfig {
        factorization,
        cosine: body.cosine,
        terms,
        terms_reason,
        cell_samples: args.cell_samples.unwrap_or(DEFAULT_CELL_SAMPLES),
        factors: name,
        brdf: body.brdf,
    })
}

/// The stage's error in the words of the flag that set the refused value (the library's speak of
/// the bake); the others as they are.
fn flagged(error: Error) -> anyhow::Error {
    let message = match &error {
        Error::Order(n) => format!("--order {n} is outside 1..={MAX_TRANSFER_ORDER}"),
        Error::Rays(n) => format!("--rays {n} is outside 1..={MAX_TRANSFER_RAYS}"),
        Error::Bounces(n) => format!("--bounces {n} is outside 1..={MAX_TRANSFER_BOUNCES}"),
        Error::Albedo(albedo) => format!("--albedo {albedo} must be a finite number ≥ 0"),
        Error::NoColours(mesh) => format!("{mesh}: --albedo mesh: the mesh holds no base colours"),
        Error::GlossyColour => "--albedo R,G,B and --albedo mesh are for diffuse transfer: a glossy bake's colour \
                                (--factors) is its BRDF's, and the surfaces it gathers from reflect a grey --albedo"
            .into(),
        Error::Offset(offset) => format!("--offset {offset} must be in [0, 0.1)"),
        Error::Terms { factors, terms, stored } => {
            format!("{factors}: --terms {terms} is outside 1..={stored}, the terms the factor file holds")
        }
        Error::CellSamples(s) => format!("--cell-samples {s} is outside 1..={MAX_CELL_SAMPLES}"),
        Error::Compression { clusters, components, most_components } => format!(
            "--clusters {clusters} --pca {components}: clusters must be in 1..={MAX_CPCA_CLUSTERS}, directions in \
             1..={most_components} (the values per vertex, at most {MAX_CPCA_DIRECTIONS})"
        ),
        Error::CompressionWork { clusters, components, vertices, per_vertex, work } => format!(
            "--clusters {clusters} --pca {components} on {vertices} vertices of {per_vertex} values: a round of \
             clustered PCA would take {work:.2e} multiply-adds, above the ceiling of {MAX_CPCA_ROUND_WORK:.0e} \
             (minutes per round); use fewer clusters or directions"
        ),
        Error::NoUvs(mesh) => format!(
            "{mesh}: no lightmap UVs (TEXCOORD_1/TEXCOORD_0, vt, or a PLY's s t / u v): --lightmap needs a UV \
             set on every vertex"
        ),
        Error::NoTexels { source_name, width, height } => {
            format!("{source_name}: a {width}x{height} lightmap (--lightmap or --texels) has no texels")
        }
        Error::Atlas { source_name, error } => format!("{source_name}: --texels makes no atlas: {error}"),
        Error::JobAtlas => "--texels is not baked as jobs: its atlas splits the vertices that --job numbers".into(),
        Error::ShEnergy(fraction) => format!("--sh-energy {fraction} must be in (0, 1]"),
        Error::JobInterreflected => {
            "--job and --join split unshadowed and shadowed bakes, diffuse or glossy; interreflected transfer is \
             baked in one run (each bounce gathers the transfer of every vertex)"
                .into()
        }
        Error::Part { file, reason } => format!("{file}: {reason} (--join takes the parts --job wrote)"),
        Error::LightmapOf { source_name, .. } => format!(
            "{source_name}: --lightmap bakes diffuse unshadowed or shadowed transfer; interreflected (its bounces \
             gather the per-vertex transfer at the rays' hits), glossy (--factors) and compressed (--clusters) \
             lightmaps are not built"
        ),
        _ => return error.into(),
    };
    anyhow::Error::msg(message)
}

impl Stage for Args {
    const NAME: &'static str = "transfer";
    fn execution(&self) -> &Execution {
        &self.run
    }
    fn run(self, ctx: &Context) -> Result<Outcome> {
        let extension = self.mesh.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        if !matches!(extension.as_deref(), Some("obj" | "ply" | "gltf" | "glb")) {
            anyhow::bail!("{}: transfer reads OBJ, PLY and glTF meshes (.obj, .ply, .gltf, .glb)", self.mesh.display());
        }
        if let Some(job) = &self.job {
            return self.run_job(job, ctx);
        }
        let Some(glb) = self.glb.as_ref() else {
            anyhow::bail!("--glb FILE is required (except with --job)");
        };
        check_json_output(&self.output, self.json)?;
        check_outputs(
            [(glb, Holds::Glb), (&self.output, Holds::Text)]
                .into_iter()
                .chain([&self.glsl, &self.hlsl, &self.wgsl].into_iter().flatten().map(|g| (g, Holds::Text))),
        )?;
        let lightmap_file = lightmap_request(&self)?.map(|(_, _, path, _)| Output::File(path));
        if let Some(file) = &lightmap_file {
            check_outputs([(file, Holds::Exr)])?;
        }
        let config = Config::try_from(&self)?;
        let mesh = self.load_mesh()?;
        let out = match &self.join {
            None => stage::run(&config, &mesh, ctx.progress()),
            Some(parts) => {
                ctx.note(format!("joining {} parts", parts.len()));
                stage::run_joined(&config, &mesh, parts.iter().map(|p| read_part(p)), ctx.progress())
            }
        }
        .map_err(flagged)
        .with_context(|| format!("cannot bake {}", self.mesh.display()))?;
        if out.summary.rays > 0 && out.summary.rays_per_second > 0.0 {
            ctx.note(format!(
                "{} vertices x {} rays in {:.2} s: {:.3e} rays/s",
                out.summary.vertices,
                out.summary.rays,
                out.summary.seconds - out.summary.bounce_seconds,
                out.summary.rays_per_second
            ));
        }
        if out.summary.bounces > 0 {
            ctx.note(format!("{} bounces in {:.2} s", out.summary.bounces, out.summary.bounce_seconds));
        }

        let mut outputs = Outputs::new();
        outputs.bytes(glb, out.glb)?;
        for (file, text) in [(&self.glsl, out.glsl), (&self.hlsl, out.hlsl), (&self.wgsl, out.wgsl)] {
            if let Some(file) = file {
                outputs.bytes(file, text.into_bytes())?;
            }
        }
        if let (Some(file), Some(lightmap)) = (&lightmap_file, out.lightmap) {
            outputs.bytes(file, lightmap.exr)?;
        }
        outputs.json(&self.output, &out.document)?;
        if self.json {
            outputs.json(&Output::Stdout, &out.summary)?;
        }
        outputs.commit()?;
        Ok(Outcome::Success)
    }
}

impl Args {
    /// The mesh, with its base colours when `--albedo mesh` asks for them.
    fn load_mesh(&self) -> Result<Mesh> {
        Ok(match self.albedo {
            Albedo::Mesh => Mesh::load_coloured(&self.mesh)?,
            _ => Mesh::load(&self.mesh)?,
        })
    }

    /// `--job I/N FILE.part`: one job's part.
    fn run_job(&self, job: &[String], ctx: &Context) -> Result<Outcome> {
        let [job, file] = job else { anyhow::bail!("--job takes I/N and FILE.part") };
        let job = Job::parse(job).map_err(|e| anyhow::anyhow!("--job {e}"))?;
        let file = Output::File(file.into());
        check_outputs([(&file, Holds::Part)])?;
        let config = Config::try_from(self)?;
        let mesh = self.load_mesh()?;
        let part = stage::run_job(&config, &mesh, job, ctx.progress())
            .map_err(flagged)
            .with_context(|| format!("cannot bake {}", self.mesh.display()))?;
        ctx.note(format!(
            "job {}/{}: vertices {}..{} of {}",
            job.index,
            job.count,
            part.vertices.start,
            part.vertices.end,
            mesh.positions.len()
        ));
        let mut outputs = Outputs::new();
        outputs.bytes(&file, part.encode())?;
        outputs.commit()?;
        Ok(Outcome::Success)
    }
}
