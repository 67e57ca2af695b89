//! `render`: clap arguments → [`render::stage::Config`] (reading the bakes it names) → one
//! library call → outputs.

mod args;

use super::common::{Context, Outcome, Stage};
use super::options::{read_sh_document, Execution};
use super::outputs::{check_outputs, Holds, Outputs};
use crate::io::{self, Output};
use crate::mesh::Mesh;
use crate::render::grid::MaterialGrid;
use crate::render::ibl::IblBake;
use crate::render::stage::{self, Config, PanelItem, Shading, StoredFactors};
use crate::render::{Camera, Scene};
use anyhow::{bail, Context as _, Result};
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
                    g.check().map_err(anyhow::Error::msg)?; // before reading the bake
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
                let bake = crate::render::transfer::TransferBake::from_glb(&file.display().to_string(), &bytes)
                    .map_err(anyhow::Error::msg)?;
                let lightmap = match &self.lightmap {
                    Some(file) => Some(Box::new(crate::render::transfer::LightmapImage::load(file, &bake)?)),
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

impl Stage for Args {
    const NAME: &'static str = "render";
    fn execution(&self) -> &Execution {
        &self.run
    }
    fn run(self, ctx: &Context) -> Result<Outcome> {
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
        let json_out = self.json.then_some(Output::Stdout);
        check_outputs(
            [
                (&self.output, Holds::Image),
                (&self.png, Holds::Png),
                (&self.error_image, Holds::Image),
                (&self.metrics, Holds::Text),
                (&self.panel, Holds::Png),
                (&json_out, Holds::Text),
            ]
            .into_iter()
            .filter_map(|(o, holds)| o.as_ref().map(|o| (o, holds))),
        )?;
        let camera = Camera::look_at(self.eye, self.target, self.fov, self.res.0, self.res.1)?;
        let scene = if self.scene == "sphere" {
            Scene::unit_sphere()
        } else {
            let mesh = Mesh::load(Path::new(&self.scene))?;
            if mesh.normals_computed {
                ctx.note(format!(
                    "{}: no vertex normals in the file; computed area-weighted normals for {} vertices",
                    self.scene,
                    mesh.positions.len()
                ));
            }
            Scene::Mesh(Box::new(mesh))
        };
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
        let out = stage::run(&config, &env, &scene, ctx.progress())?;

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
        if let Some(o) = &json_out {
            outputs.json(o, &out.summary)?;
        }
        outputs.commit()?;
        if let Some((doc, _)) = &out.comparison {
            ctx.note(format!("vs {}: {}", doc.body.reference, doc.body.metrics));
        }
        Ok(Outcome::Success)
    }
}
