//! `prefilter`: clap arguments → [`prefilter::stage::Config`] → one library call → outputs.
//!
//! [`prefilter::stage::Config`]: crate::prefilter::stage::Config

mod args;

use super::common::{Context, Outcome, Stage};
use super::options::Execution;
use super::options::{check_json_output, read_sh_document, EnvArgs};
use super::outputs::{check_output_dir, check_outputs, Holds, Outputs};
use crate::io::Output;
use crate::limits::MAX_VERIFY_TEXELS;
use crate::prefilter::model::ModelError;
use crate::prefilter::pipeline::{Lighting, PrefilterError};
use crate::prefilter::ring_free::MapsFrom;
use crate::prefilter::stage::{self, Config, MapRequest};
use crate::prefilter::verify::{Verification, VerifyError};
use crate::sh::window::Window;
use anyhow::{anyhow, bail, Result};
pub use args::*;
use std::path::PathBuf;

impl TryFrom<&Args> for Config {
    type Error = anyhow::Error;
    fn try_from(args: &Args) -> Result<Config> {
        Ok(Config {
            brdf: args.brdf.clone(),
            cosine: !args.no_cosine,
            method: args.method,
            epsilon: args.epsilon,
            orders: args.order,
            max_p: args.max_p as usize,
            order_rule: args.order_rule,
            bright: args.bright,
            window: args.window,
            bound: args.bound,
            size: args.size,
            output_layout: args.output_layout.layout(),
            shrm_file: args.shrm.as_ref().map(|p| p.display().to_string()),
            global: args.global,
            maps: args
                .map_files()?
                .into_iter()
                .map(|(file, view)| MapRequest { file: file.display().to_string(), view })
                .collect(),
            kautz_mccool_slices: if args.kautz_mccool.is_some() { args.slices as usize } else { 0 },
            irradiance: args.irradiance.is_some(),
            verify: args.verify.map(|n| n as usize),
            source: match (&args.env, &args.sh) {
                (Some(p), _) | (None, Some(p)) => crate::io::read::display_path(p).display().to_string(),
                (None, None) => String::new(),
            },
            args: std::env::args().collect(),
        })
    }
}

impl Stage for Args {
    const NAME: &'static str = "prefilter";
    fn execution(&self) -> &Execution {
        &self.run
    }
    fn run(self, ctx: &Context) -> Result<Outcome> {
        let document = self.document_output();
        if let Some(o) = &document {
            check_json_output(o, self.json)?;
        }
        if self.sh.is_some() && self.orient.flip_vertical {
            bail!("--flip-vertical turns an environment map as it is read; an SH document is already in its frame");
        }
        // --icosahedral and --views-dir are directories this run creates; every other file goes
        // into a directory that exists.
        let map_files = self.map_files()?;
        let new_dirs: Vec<&PathBuf> = self.icosahedral.iter().chain(&self.views_dir).collect();
        new_dirs.iter().try_for_each(|dir| check_output_dir(dir))?;
        let file = |p: &PathBuf| Output::File(p.clone());
        let maps: Vec<Output> = self.reflection_map.iter().chain(&self.irradiance).map(file).collect();
        let layers: Vec<Output> = self.shrm.iter().chain(&self.kautz_mccool).map(file).collect();
        check_outputs(
            (document.iter().map(|o| (o, Holds::Text)))
                .chain(maps.iter().map(|o| (o, Holds::Image)))
                .chain(layers.iter().map(|o| (o, Holds::Exr))),
        )?;
        let config = Config::try_from(&self)?;

        let env_args = self.env.as_ref().map(|path| EnvArgs {
            path: path.clone(),
            layout: self.layout,
            negative: self.negative,
            orient: self.orient,
        });
        let map = env_args.as_ref().map(|e| e.load(ctx)).transpose()?;
        let coefficients = match &self.sh {
            Some(path) => Some(read_sh_document(path)?),
            None => None,
        };
        let lighting = match (&map, &coefficients) {
            (Some(m), _) => Lighting::Map(m),
            (None, Some(c)) => Lighting::Coefficients(c),
            (None, None) => bail!("give an environment map or --sh FILE"),
        };
        let out = stage::run(&config, lighting, ctx.progress()).map_err(worded)?;
        let in_angle = out.document.body.bake.as_ref().is_some_and(|b| b.maps == MapsFrom::Angle);
        if in_angle && self.window != Window::Nonneg && self.shrm.is_none() && self.kautz_mccool.is_none() {
            ctx.note(format_args!(
                "--window {} has no effect: the reflection maps were integrated in angle, with no spherical \
                 harmonics to window (docs/prefilter.md, \"Maps in angle\")",
                self.window.name()
            ));
        }
        if let Some(v) = &out.summary.verification {
            ctx.note(verification_note(v));
        }

        let mut outputs = Outputs::new();
        for dir in new_dirs {
            outputs.create_dir(dir)?;
        }
        for ((path, _), image) in map_files.iter().zip(&out.maps) {
            outputs.image(&Output::File(path.clone()), image, self.exposure.stops)?;
        }
        if let (Some(path), Some(image)) = (&self.irradiance, &out.irradiance) {
            outputs.image(&Output::File(path.clone()), image, self.exposure.stops)?;
        }
        for (path, layers) in [(&self.shrm, &out.shrm_layers), (&self.kautz_mccool, &out.kautz_mccool)] {
            if let (Some(path), Some(layers)) = (path, layers) {
                outputs.layers(&Output::File(path.clone()), layers)?;
            }
        }
        if let Some(o) = &document {
            outputs.json(o, &out.document)?;
        }
        if self.json {
            outputs.json(&Output::Stdout, &out.summary)?;
        }
        outputs.commit()?;
        Ok(Outcome::Success)
    }
}

/// The library's errors that come from a flag, worded with the flag (the rest as they are).
fn worded(error: stage::Error) -> anyhow::Error {
    use stage::Error as E;
    let message = match &error {
        E::Epsilon(e) => format!("--epsilon must be in (0, 1), got {e}"),
        E::IrradianceNeedsLambert => {
            "an irradiance map needs --brdf lambert (it is Lambert's reflection map × π/albedo)".into()
        }
        E::AngularMapsOnly => "--method angular writes reflection maps only (and the irradiance map)".into(),
        E::AngularNeedsMap => "--method angular needs the environment map, not SH coefficients".into(),
        E::AngularTakesNoOrders => {
            "--method angular takes no --order: it uses no spherical harmonics (ε is its truncation)".into()
        }
        E::VerifyNeedsMap => {
            "--verify needs the environment map, not SH coefficients (the exact values integrate the map)".into()
        }
        E::Verify(VerifyError::Texels(n)) => format!("--verify {n}: must be in 1..={MAX_VERIFY_TEXELS}"),
        E::Verify(VerifyError::ZeroReference(_)) => format!("--verify: {error}"),
        E::Prefilter { error: PrefilterError::Model(ModelError::Unreachable { .. }), .. } => {
            format!("{error}; use a larger --epsilon")
        }
        E::Prefilter { error: PrefilterError::LightingOrder { need, .. }, .. } => {
            format!("{error}: re-run sh-project with --order {need} (or give the environment map)")
        }
        _ => return error.into(),
    };
    anyhow!(message)
}

/// One line on `--verify`: the map with the largest per-texel error, in the figures a person sees.
fn verification_note(v: &Verification) -> String {
    let worst = v.maps.iter().max_by(|a, b| a.max_texel_error.total_cmp(&b.max_texel_error));
    let Some(m) = worst else { return "verify: no map to check".into() };
    let of = if v.maps.len() > 1 { format!(" (the worst of {} maps)", v.maps.len()) } else { String::new() };
    format!(
        "verify: {}{of}: {} texels against the angular integral (ε = {:e}): {} negative, per texel max {:.3} % \
         (at ({}, {}): mean RGB {:.4e}, exact {:.4e}) and p99 {:.3} %, rel RMS {:.3} %",
        m.map,
        m.texels,
        v.epsilon,
        m.negative,
        100.0 * m.max_texel_error,
        m.worst.x,
        m.worst.y,
        m.worst.value.iter().sum::<f64>() / 3.0,
        m.worst.exact.iter().sum::<f64>() / 3.0,
        100.0 * m.p99_texel_error,
        100.0 * m.rel_error
    )
}
