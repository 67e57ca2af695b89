//! `render`: clap arguments → [`render::stage::Config`] (reading the bakes it names) → one
//! library call → outputs.
//!
//! [`render::stage::Config`]: crate::render::stage::Config

mod args;

use super::common::{Context, Outcome, Stage};
use super::options::{read_sh_document, Execution};
use super::outputs::{check_outputs, Holds, Outputs};
use crate::io::{self, Output};
use crate::mesh::Mesh;
use crate::metrics::CompareError;
use crate::render::grid::{GridError, MaterialGrid};
use crate::render::ibl::IblBake;
use crate::render::stage::{self, Config, PanelItem, Shading, StoredFactors};
use crate::render::transfer::{LightmapError, LightmapImage, OtherMesh};
use crate::render::{Camera, Scene};
use anyhow::{anyhow, bail, Context as _, Result};
pub use args::*;

use std::path::Path;

impl Args {
    /// The mode with the bakes it reads (documents and their EXRs).
    fn shading(&self) -> Result<Shading> {
        Ok(match self.shading {
            ShadingArg::Irradiance => Shading::Irradiance {
                order: self.order,
                coefficients: self.sh.as_deref().map(read_sh_document).transpose()?,
                window: self.window.unwrap_or_default(),
            },
            ShadingArg::Shrm => {
                let doc =
                    self.shrm.as_ref().context("--shading shrm needs --shrm SHRM.json (from prefilter --shrm)")?;
                let (shrm, body) = crate::render::reflection::load(doc)?;
                Shading::Shrm { shrm, body: Box::new(body), window: self.window.unwrap_or_default() }
            }
            ShadingArg::Factored => {
                let factors = self.stored_factors()?;
                Shading::Factored {
                    terms: self.terms,
                    factors,
                    resolution: self.factor_resolution,
                    cell_samples: self.cell_samples,
                    normal_table: self.normal_table,
                    bright: self.bright,
                }
            }
            ShadingArg::Ibl => {
                let doc =
                    self.ibl.as_ref().context("--shading ibl needs --ibl DIR (from ibl -o DIR) or DIR/ibl.json")?;
                // The bake's directory stands for its manifest.
                let doc = if doc.is_dir() { doc.join("ibl.json") } else { doc.clone() };
                let grid = self.grid.then(|| MaterialGrid {
                    roughness: self.grid_roughness.clone(),
                    metalness: self.grid_metalness.clone(),
                });
                if let Some(g) = &grid {
                    g.check().map_err(grid_error)?; // before reading the bake
                }
                Shading::Ibl { bake: Box::new(IblBake::load(&doc)?), grid }
            }
            ShadingArg::Transfer => {
                let file = self
                    .transfer
                    .as_ref()
                    .context("--shading transfer needs --transfer FILE.glb (from transfer --glb)")?;
                let bytes = crate::io::read_bytes(file, "glTF binary", crate::limits::max_file_bytes(), |start| {
                    if start.starts_with(b"glTF") {
                        Ok(())
                    } else {
                        Err("not a .glb (no glTF magic)".into())
                    }
                })?;
                let bake = crate::render::transfer::TransferBake::from_glb(&file.display().to_string(), &bytes)?;
                let lightmap = match &self.lightmap {
                    Some(file) => Some(Box::new(LightmapImage::load(file, &bake).map_err(lightmap_error)?)),
                    None => None,
                };
                Shading::Transfer { bake: Box::new(bake), factors: self.stored_factors()?, lightmap }
            }
            ShadingArg::Reference => Shading::Reference { integrand: self.integrand },
        })
    }

    /// The factorization `--factors` names, read back with its factor file.
    fn stored_factors(&self) -> Result<Option<Box<StoredFactors>>> {
        let Some(doc) = &self.factors else { return Ok(None) };
        let (body, factorization) = crate::factor::document::load(doc)?;
        let name = doc.display().to_string();
        Ok(Some(Box::new(StoredFactors { name, factorization, cosine: body.cosine, brdf: body.brdf })))
    }

    /// The library's errors that come from a flag, worded with the flag and its value (as
    /// ripgrep's `HiArgs` words its own); the others as they are.
    fn flag_error(&self, error: stage::Error) -> anyhow::Error {
        use stage::Error as E;
        let file = |path: &Option<std::path::PathBuf>| path.as_ref().map_or(String::new(), |p| p.display().to_string());
        let message = match error {
            E::Compare { reference, error: CompareError::Size { rw, rh, w, h } } => {
                format!("{reference}: the reference is {rw}x{rh}, the render is {w}x{h} (--res)")
            }
            E::EnvRotation(degrees) => format!("--env-rotation {degrees} is outside -360..=360 degrees"),
            E::EnvRotationShading { .. } => "--env-rotation is for --shading transfer and reference".into(),
            E::NotLambert { shading, brdf } => {
                format!("--shading {shading} shades Lambertian surfaces; --brdf {brdf} is not lambert")
            }
            E::ShOrder { available, wanted } => {
                format!("{}: the coefficients have order {available}, --order asks for {wanted}", file(&self.sh))
            }
            E::ShrmBrdf { shrm, brdf } => {
                format!("{}: the SHRM was computed for {shrm}, --brdf says {brdf}", file(&self.shrm))
            }
            E::NoTerms => "--terms must be at least 1".into(),
            E::CellSamples(n) => format!("--cell-samples {n} must be in 1..=8"),
            E::FactorsBrdf { factors, factored, brdf } => {
                format!("{factors}: the factorization is of {factored}, --brdf says {brdf}")
            }
            E::FactorsResolution { factors, stored, asked } => format!(
                "{factors}: a factorization of another resolution: n = {stored}, --factor-resolution asks for {asked}"
            ),
            E::FactorsTerms { factors, stored, asked } => format!(
                "{factors}: the factor file holds {stored} terms, --terms asks for {asked} (factor-brdf --terms {asked})"
            ),
            E::FactorResolution(n) => format!("--factor-resolution {n} must be in 2..=256"),
            E::TermsAboveRank { terms, resolution } => format!(
                "--terms {terms} is more than the {} a factorization at --factor-resolution {resolution} has",
                resolution * resolution
            ),
            E::NotGltf { brdf } => format!(
                "--shading ibl shades glTF metallic-roughness materials; --brdf {brdf} is not gltf:base=R/G/B,metalness=M,roughness=R"
            ),
            E::GridReferences => "--grid renders its own references: no --compare or --panel-item".into(),
            E::TransferOfSphere => {
                "--shading transfer relights a mesh: --scene FILE.obj, the mesh the bake is of".into()
            }
            E::OtherMesh(OtherMesh::Size { bake, bake_vertices, bake_triangles, vertices, triangles }) => format!(
                "{bake}: the transfer is of a mesh of {bake_vertices} vertices and {bake_triangles} triangles, \
                 the --scene mesh {} has {vertices} and {triangles}",
                self.scene
            ),
            E::OtherMesh(OtherMesh::Vertex { bake, vertex }) => format!(
                "{bake}: vertex {vertex} is not where the --scene mesh {} has it: the transfer is of another mesh",
                self.scene
            ),
            E::TransferBrdf { bake, baked, brdf } => format!("{bake}: the transfer holds {baked}, --brdf says {brdf}"),
            E::FactorsForDiffuse { bake } => format!("{bake}: a diffuse transfer; --factors is for glossy bakes"),
            E::DiffuseTransferNotLambert { bake, brdf } => {
                format!("{bake}: a diffuse transfer relights a lambert BRDF; --brdf {brdf} is not lambert")
            }
            E::TransferAlbedo { bake, albedo, brdf } => {
                format!("{bake}: the transfer was baked with albedo {albedo}, --brdf says {brdf}")
            }
            E::ColouredTransferAlbedo { bake, brdf } => format!(
                "{bake}: the transfer holds a coloured albedo (transfer --albedo R,G,B or mesh), so its colour is in \
                 the bake: relight it with --brdf lambert (albedo 1), not {brdf}"
            ),
            E::NoLightmapUvs { lightmap } => format!(
                "{lightmap}: the --scene mesh {} has no lightmap UVs (TEXCOORD_1/TEXCOORD_0, vt, or a PLY's s t / u v) to look the lightmap up with",
                self.scene
            ),
            E::Grid(grid) => return grid_error(grid),
            other => return other.into(),
        };
        anyhow!(message)
    }

    /// The panel items: `LABEL=FILE.exr` read, `LABEL=-` for this render.
    fn panel_items(&self) -> Result<Option<Vec<PanelItem>>> {
        if self.panel.is_none() {
            if !self.panel_item.is_empty() {
                bail!("--panel-item needs --panel FILE.png");
            }
            return Ok(None);
        }
        let mut items = Vec::new();
        for (label, file) in &self.panel_item {
            let image = if file.as_os_str() == "-" { None } else { Some(io::image::read_image(file)?) };
            items.push(PanelItem { label: label.clone(), image });
        }
        if items.iter().filter(|item| item.image.is_none()).count() > 1 {
            bail!("--panel-item LABEL=- (this render) may be given once");
        }
        Ok(Some(items))
    }
}

/// A `--lightmap` that cannot relight the `--transfer` bake, with what writes one.
fn lightmap_error(error: LightmapError) -> anyhow::Error {
    match error {
        LightmapError::MissingLayer { .. } => anyhow!("{error} (transfer --lightmap writes one)"),
        LightmapError::Glossy { .. } => anyhow!("{error} (--lightmap goes with a diffuse --transfer bake)"),
        other => other.into(),
    }
}

/// A material grid's faults worded with the flags that set it.
fn grid_error(error: GridError) -> anyhow::Error {
    match error {
        GridError::Empty => anyhow!("--grid needs at least one --grid-roughness and one --grid-metalness"),
        GridError::TooManyCells { columns, rows } => anyhow!(
            "--grid-roughness × --grid-metalness: {columns} × {rows} cells is more than the {} a grid renders \
             (each twice, the reference at full cost)",
            crate::limits::MAX_GRID_CELLS
        ),
        GridError::Roughness(r) => {
            anyhow!("--grid-roughness {r} must be in (0, 1] (r = 0, the mirror, has no GGX lobe)")
        }
        GridError::Metalness(m) => anyhow!("--grid-metalness {m} must be in [0, 1]"),
        other => other.into(),
    }
}

impl Args {
    /// Flags that make no sense together, refused before anything is read.
    fn check_flags(&self) -> Result<()> {
        if self.outputs().next().is_none() && !self.json {
            bail!("nothing to write: give -o FILE.exr, --png, --panel or --json");
        }
        if (self.error_image.is_some() || self.metrics.is_some()) && self.compare.is_none() {
            bail!("--error-image and --metrics need --compare REF.exr");
        }
        if self.window.is_some() && !matches!(self.shading, ShadingArg::Irradiance | ShadingArg::Shrm) {
            bail!("--window is for --shading irradiance and shrm (the SH modes)");
        }
        if self.grid && self.shading != ShadingArg::Ibl {
            bail!("--grid is for --shading ibl");
        }
        if self.transfer.is_some() && self.shading != ShadingArg::Transfer {
            bail!("--transfer is for --shading transfer");
        }
        Ok(())
    }

    /// The outputs, with `--json`'s stdout, each checked for what it can hold.
    fn check_outputs(&self, json_out: &Option<Output>) -> Result<()> {
        check_outputs(
            [
                (&self.output, Holds::Image),
                (&self.png, Holds::Png),
                (&self.error_image, Holds::Image),
                (&self.metrics, Holds::Text),
                (&self.panel, Holds::Png),
                (json_out, Holds::Text),
            ]
            .into_iter()
            .filter_map(|(o, holds)| o.as_ref().map(|o| (o, holds))),
        )
    }

    /// `--scene`: the unit sphere, or the mesh read (noting normals it had to compute).
    fn scene(&self, ctx: &Context) -> Result<Scene> {
        if self.scene == "sphere" {
            return Ok(Scene::unit_sphere());
        }
        let mesh = Mesh::load(Path::new(&self.scene))?;
        if mesh.normals_computed {
            ctx.note(format!(
                "{}: no vertex normals in the file; computed area-weighted normals for {} vertices",
                self.scene,
                mesh.positions.len()
            ));
        }
        Ok(Scene::Mesh(Box::new(mesh)))
    }

    /// Writes what the flags ask for of `out`, all or nothing.
    fn write(&self, out: &stage::Output, json_out: &Option<Output>) -> Result<()> {
        let mut outputs = Outputs::new();
        let stops = self.exposure.stops;
        for o in self.output.iter().chain(&self.png) {
            outputs.image(o, &out.frame.image, stops)?;
        }
        if let Some((doc, error_image)) = &out.comparison {
            if let Some(o) = &self.error_image {
                outputs.image(o, error_image, stops)?;
            }
            if let Some(o) = &self.metrics {
                outputs.json(o, doc)?;
            }
        }
        if let (Some(o), Some(panel)) = (&self.panel, &out.panel) {
            outputs.image(o, panel, stops)?;
        }
        if let Some(o) = json_out {
            outputs.json(o, &out.summary)?;
        }
        outputs.commit()
    }
}

impl Stage for Args {
    const NAME: &'static str = "render";
    fn execution(&self) -> &Execution {
        &self.run
    }
    fn run(self, ctx: &Context) -> Result<Outcome> {
        self.check_flags()?;
        let json_out = self.json.then_some(Output::Stdout);
        self.check_outputs(&json_out)?;
        let camera = Camera::look_at(self.eye, self.target, self.fov, self.res.0, self.res.1)?;
        let scene = self.scene(ctx)?;
        let compare = match &self.compare {
            Some(p) => Some((p.display().to_string(), io::image::read_image(p)?)),
            None => None,
        };
        let config = Config {
            brdf: self.brdf.clone(),
            shading: self.shading()?,
            camera,
            env_rotation: self.env_rotation,
            compare,
            panel: self.panel_items()?,
            label: self.label.clone(),
            exposure: self.exposure.stops,
            output_name: self.output.as_ref().map(|o| o.display()),
            args: std::env::args().collect(),
        };
        let env = self.input.load(ctx)?;
        let out = stage::run(&config, &env, &scene, ctx.progress()).map_err(|e| self.flag_error(e))?;
        self.write(&out, &json_out)?;
        if let Some((doc, _)) = &out.comparison {
            ctx.note(format!("vs {}: {}", doc.body.reference, doc.body.metrics));
        }
        Ok(Outcome::Success)
    }
}
