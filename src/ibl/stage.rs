//! The `ibl` stage as one library call: an environment map in, what a glTF/PBR engine loads out
//! — the GGX-prefiltered specular cube with its mip chain, the irradiance cube, order-2 SH
//! irradiance with shader snippets, the split-sum DFG table and the `prtkit.ibl` manifest
//! (`docs/ibl.md`) — as values; the caller encodes the files ([`crate::io::texture`] for the
//! textures, as `cli/outputs.rs` does).
//!
//! **Levels.** Level k of an L-level chain has face size `size >> k` and perceptual roughness
//! r_k = k/(L − 1) (`linear`), or Filament's r_k = 1 − √(1 − k/(L − 1)), the inverse of its
//! lod = r(2 − r) (`filament`). Level 0 (r = 0, a mirror) is the environment resampled; every
//! other level is the split-sum GGX prefilter (Karis 2013, [`crate::brdf::ggx::SplitSumLobe`]), by
//! whichever exact method the cost model finds cheaper ([`choose_method`]): the zonal filter on a
//! lat-long grid ([`super::frequency`]) or the angular cone sum over a cube pyramid
//! ([`super::angular`]). Neither samples at random.
//!
//! **Frame.** Output directions d_out = M d_prtkit with M = U·R_z(θ)·S: S mirrors prtkit's y
//! (`--mirror`), R_z turns by `--rotate` degrees about prtkit's up axis, U takes prtkit's +Z to
//! glTF's +Y ([`super::cube::WORLD_FROM_PRTKIT`]; the identity with `--up z`). Everything is
//! filtered by direction, so the frame change is exact: texel d_out of a level is B(Mᵀ d_out).
//!
//! **Measured, not assumed.** With `samples` > 0 every level with r > 0 and the irradiance cube
//! are compared with the angular integral of the input ([`super::reference`]) on that many
//! texels; the manifest records the errors. The reference's values at those texels need only
//! the input and the levels' sizes, so they are summed beside the bake (`expect`).

use super::angular::{AngularError, AngularOptions, AngularPrefilter};
use super::cube::{CubeError, CubeMap, CubeMipChain, WORLD_FROM_PRTKIT};
use super::dfg::{self, DfgError, DfgTable, DfgVariant};
use super::frequency::{FilteredSphere, LatLongSource};
use super::manifest::{self, Costs, IblBody, Level, ShBody, Timings};
use super::reference::{Expected, Reference, ReferenceError};
use super::sh_irradiance::IrradianceSh;
use crate::brdf::ggx::{GgxError, SplitSumLobe};
use crate::envmap::zonal::ZonalError;
use crate::envmap::{self, EnvMap, EnvMapError, Layout, Orientation};
use crate::io::gpu_format::{TexelFormat, Texture};
use crate::io::texture::Container;
use crate::io::{Document, Provenance};
use crate::limits::{LimitError, MAX_IBL_FACE_SIZE};
use crate::progress::Progress;
use crate::sh::project::ProjectError;
use glam::{DMat3, DVec3};
use rayon::prelude::*;
use std::borrow::Cow;
use std::time::Instant;

/// How level index maps to roughness.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum RoughnessMap {
    /// r_k = k/(L − 1).
    Linear,
    /// Filament's: r_k = 1 − √(1 − k/(L − 1)) (the inverse of lod = r(2 − r)).
    Filament,
}

impl RoughnessMap {
    /// Roughness of level k of `levels`.
    pub fn roughness(self, k: usize, levels: usize) -> f64 {
        if levels < 2 {
            return 0.0;
        }
        let lod = k as f64 / (levels - 1) as f64;
        match self {
            RoughnessMap::Linear => lod,
            RoughnessMap::Filament => 1.0 - (1.0 - lod).max(0.0).sqrt(),
        }
    }

    /// Name.
    pub fn name(self) -> &'static str {
        match self {
            RoughnessMap::Linear => "linear",
            RoughnessMap::Filament => "filament",
        }
    }

    fn formula(self) -> &'static str {
        match self {
            RoughnessMap::Linear => "r_k = k / (levels - 1)",
            RoughnessMap::Filament => {
                "r_k = 1 - sqrt(1 - k / (levels - 1)), the inverse of Filament's lod = r (2 - r) (lodToPerceptualRoughness)"
            }
        }
    }
}

/// The output frame's up axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Up {
    /// glTF: prtkit's +Z becomes +Y.
    Y,
    /// prtkit's frame kept.
    Z,
}

/// Per-level method.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// The environment resampled (r = 0).
    Resample,
    /// Zonal filter on a lat-long grid.
    Zonal,
    /// Angular cone sums over a cube pyramid.
    Angular,
}

impl Method {
    /// Name in the manifest.
    pub fn name(self) -> &'static str {
        match self {
            Method::Resample => "resample",
            Method::Zonal => "zonal",
            Method::Angular => "angular",
        }
    }
}

/// Force a method instead of the cost model (tests, studies).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum MethodChoice {
    /// The cheaper by [`choose_method`].
    #[default]
    Auto,
    /// Always zonal.
    Zonal,
    /// Always angular.
    Angular,
}

/// What `ibl` computes.
#[derive(Clone, Debug)]
pub struct Config {
    /// Face size of level 0 (power of two).
    pub size: usize,
    /// Face size of the last level (power of two, ≤ size).
    pub min_size: usize,
    /// Face size of the irradiance cube (power of two).
    pub irradiance_size: usize,
    /// Level → roughness.
    pub roughness_map: RoughnessMap,
    /// Texel format of the cubes (the DFG table is RG16F, or RG32F with RGBA32F).
    pub format: TexelFormat,
    /// Container.
    pub container: Container,
    /// Output up axis.
    pub up: Up,
    /// Rotation about the up axis in degrees.
    pub rotate_degrees: f64,
    /// Mirror the environment.
    pub mirror: bool,
    /// Clamp input radiance to at most this (before filtering).
    pub clamp: Option<f64>,
    /// DFG variant.
    pub dfg: DfgVariant,
    /// DFG side.
    pub dfg_size: usize,
    /// Texels per level measured against the angular reference (0: none).
    pub samples: usize,
    /// Method choice.
    pub method: MethodChoice,
    /// Input name, for the manifest.
    pub source: String,
    /// Command line, for provenance.
    pub args: Vec<String>,
}

impl Default for Config {
    fn default() -> Self {
        Config {
            size: 256,
            min_size: 8,
            irradiance_size: 32,
            roughness_map: RoughnessMap::Linear,
            format: TexelFormat::Rgba16Float,
            container: Container::Ktx2,
            up: Up::Y,
            rotate_degrees: 0.0,
            mirror: false,
            clamp: None,
            dfg: DfgVariant::ScaleBias,
            dfg_size: 128,
            samples: 64,
            method: MethodChoice::Auto,
            source: String::new(),
            args: Vec::new(),
        }
    }
}

/// Which face size of the bake a value is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FaceSize {
    /// The first (largest) specular level's, [`Config::size`].
    First,
    /// The last (smallest) specular level's, [`Config::min_size`].
    Last,
    /// The irradiance cube's, [`Config::irradiance_size`].
    Irradiance,
}

impl std::fmt::Display for FaceSize {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            FaceSize::First => "the first specular level",
            FaceSize::Last => "the last specular level",
            FaceSize::Irradiance => "the irradiance cube",
        })
    }
}

/// Errors of the stage.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A face size that is not a power of two in 1..=[`MAX_IBL_FACE_SIZE`].
    #[error("the face size {size} of {which} is not a power of two between 1 and {MAX_IBL_FACE_SIZE}")]
    Size {
        /// Whose face size.
        which: FaceSize,
        /// The value.
        size: usize,
    },
    /// The last specular level larger than the first.
    #[error("the last specular level's face size {min} is larger than the first's, {size}")]
    MinSize {
        /// The last level's face size.
        min: usize,
        /// The first level's face size.
        size: usize,
    },
    /// A rotation about the up axis that is not a finite angle.
    #[error("the rotation {0} degrees is not a finite angle")]
    Rotation(f64),
    /// A radiance ceiling that is not positive (or NaN).
    #[error("the radiance ceiling {0} is not positive")]
    Clamp(f64),
    /// The cubes need an RGB format.
    #[error("{0} is a two-channel format; the cubes need rgba16f, rgba32f, b10g11r11 or e5b9g9r9")]
    Format(&'static str),
    /// Environment geometry.
    #[error(transparent)]
    EnvMap(#[from] EnvMapError),
    /// Zonal filter.
    #[error(transparent)]
    Zonal(#[from] ZonalError),
    /// Cube geometry.
    #[error(transparent)]
    Cube(#[from] CubeError),
    /// Angular prefilter.
    #[error(transparent)]
    Angular(#[from] AngularError),
    /// The bake would need more memory than the budget allows.
    #[error(transparent)]
    Memory(#[from] LimitError),
    /// The reference.
    #[error("angular reference: {0}")]
    Reference(#[from] ReferenceError),
    /// The SH projection (an input too coarse for order 2).
    #[error("the SH irradiance")]
    Project(#[from] ProjectError),
    /// GGX.
    #[error(transparent)]
    Ggx(#[from] GgxError),
    /// DFG, its table side among them.
    #[error(transparent)]
    Dfg(#[from] DfgError),
}

/// What `ibl` produces: the values of every file of DIR (`docs/ibl.md`), which the caller
/// encodes with [`crate::io::texture`] and [`Document::to_json`] — [`Output::textures`] and
/// [`Output::shaders`] name each as the manifest does.
#[derive(Clone, Debug)]
pub struct Output {
    /// The manifest, `ibl.json`.
    pub document: Document<IblBody>,
    /// The SH document.
    pub sh_document: Document<ShBody>,
    /// The SH.
    pub sh: IrradianceSh,
    /// The specular chain (f32, before packing).
    pub specular: CubeMipChain,
    /// The irradiance cube E/π (f32).
    pub irradiance: CubeMap,
    /// The DFG table.
    pub dfg: DfgTable,
    /// The container of the three texture files.
    pub container: Container,
    /// The texel format of the cubes.
    pub format: TexelFormat,
    /// The texel format of the DFG table: RG16F, or RG32F beside RGBA32F cubes.
    pub dfg_format: TexelFormat,
}

impl Output {
    /// The texture files — the specular chain, the irradiance cube, the DFG table — each as
    /// (its name in DIR, its texels, the format to pack them in).
    pub fn textures(&self) -> [(&str, Texture<'_>, TexelFormat); 3] {
        let body = &self.document.body;
        [
            (&body.specular.file, self.specular.as_texture(), self.format),
            (&body.irradiance.file, self.irradiance.as_texture(), self.format),
            (&body.dfg.file, self.dfg.as_texture(), self.dfg_format),
        ]
    }

    /// The SH shader snippets — GLSL, HLSL, WGSL — each as (its name in DIR, its text), naming
    /// the frame as the documents' conventions do.
    pub fn shaders(&self) -> [(&str, String); 3] {
        let (names, frame) = (&self.document.body.sh.shaders, &self.document.conventions.frame);
        [(&names[0], self.sh.glsl(frame)), (&names[1], self.sh.hlsl(frame)), (&names[2], self.sh.wgsl(frame))]
    }
}

fn check_size(which: FaceSize, size: usize) -> Result<(), Error> {
    if size == 0 || !size.is_power_of_two() || size > MAX_IBL_FACE_SIZE {
        return Err(Error::Size { which, size });
    }
    Ok(())
}

impl Config {
    /// Checks sizes and numbers.
    pub fn check(&self) -> Result<(), Error> {
        check_size(FaceSize::First, self.size)?;
        check_size(FaceSize::Last, self.min_size)?;
        check_size(FaceSize::Irradiance, self.irradiance_size)?;
        if self.min_size > self.size {
            return Err(Error::MinSize { min: self.min_size, size: self.size });
        }
        if !self.rotate_degrees.is_finite() {
            return Err(Error::Rotation(self.rotate_degrees));
        }
        if let Some(c) = self.clamp {
            if c.is_nan() || c <= 0.0 {
                return Err(Error::Clamp(c));
            }
        }
        if matches!(self.format, TexelFormat::Rg16Float | TexelFormat::Rg32Float) {
            return Err(Error::Format(self.format.name()));
        }
        Ok(dfg::check_size(self.dfg_size)?)
    }

    /// Number of specular levels.
    pub fn levels(&self) -> usize {
        (self.size / self.min_size).trailing_zeros() as usize + 1
    }

    /// The specular levels the split-sum lobe filters, every one but level 0 (the resampled
    /// input): (k, face size, r).
    fn filtered_levels(&self) -> impl Iterator<Item = (usize, usize, f64)> + '_ {
        let levels = self.levels();
        (1..levels).map(move |k| (k, self.size >> k, self.roughness_map.roughness(k, levels)))
    }

    /// The texel format of the DFG table: two channels, single floats beside RGBA32F cubes.
    pub fn dfg_format(&self) -> TexelFormat {
        if self.format == TexelFormat::Rgba32Float {
            TexelFormat::Rg32Float
        } else {
            TexelFormat::Rg16Float
        }
    }

    /// The memory a bake of an input of `input_texels` holds at its peak, planned before any of
    /// it is allocated: a working copy of the input (RGB f32, made only when it is clamped or
    /// resampled), the measurement's grids beside the bake (at most RGB f32 per input texel: a
    /// copy of an input narrower than 512 columns, or the box filtering of a large one with its
    /// deviations), every specular level and the irradiance cube (RGB f32), and their files
    /// encoded (`format`) while the values are still held.
    pub fn planned_bytes(&self, input_texels: u64) -> u128 {
        let cube_texels: u128 = (0..self.levels()).map(|k| 6 * ((self.size >> k) as u128).pow(2)).sum::<u128>()
            + 6 * (self.irradiance_size as u128).pow(2);
        2 * 12 * input_texels as u128 + cube_texels * (12 + self.format.texel_bytes() as u128)
    }

    /// M: output frame from prtkit's frame (module docs).
    pub fn world_from_prtkit(&self) -> DMat3 {
        let up = match self.up {
            Up::Y => WORLD_FROM_PRTKIT,
            Up::Z => DMat3::IDENTITY,
        };
        let mirror = if self.mirror { DMat3::from_diagonal(DVec3::new(1.0, -1.0, 1.0)) } else { DMat3::IDENTITY };
        up * DMat3::from_rotation_z(self.rotate_degrees.to_radians()) * mirror
    }

    fn frame(&self, input: Orientation) -> manifest::Frame {
        let m = self.world_from_prtkit();
        manifest::Frame {
            up: match self.up {
                Up::Y => "y".into(),
                Up::Z => "z".into(),
            },
            rotate_degrees: self.rotate_degrees,
            mirror: self.mirror,
            flip_vertical: input == Orientation::FlipVertical,
            world_from_prtkit: [0, 1, 2].map(|r| [m.x_axis[r], m.y_axis[r], m.z_axis[r]]),
            faces: manifest::FACE_ORDER.iter().map(|s| s.to_string()).collect(),
            face_orientation: manifest::FACE_ORIENTATION.into(),
        }
    }

    fn frame_words(&self, input: Orientation) -> String {
        let mut turned = match (self.rotate_degrees != 0.0, self.mirror) {
            (false, false) => String::new(),
            (r, m) => format!(
                ", environment{}{}",
                if m { " mirrored" } else { "" },
                if r { format!(" rotated {} degrees about up", self.rotate_degrees) } else { String::new() }
            ),
        };
        if input == Orientation::FlipVertical {
            turned.push_str(", input flipped vertically on reading");
        }
        match self.up {
            Up::Y => format!("glTF world, +Y up (prtkit +Z -> +Y, +X kept, prtkit +Y -> -Z){turned}"),
            Up::Z => format!("prtkit, +Z up{turned}"),
        }
    }
}

/// Seconds per unit of [`super::frequency::zonal_cost`] and per angular kernel evaluation, measured
/// on one core of the development machine (`grace_latlong.exr`: the zonal filter of a 256 × 128
/// grid, 7.9e6 units, in 0.044 s; the angular 32² level at r = 0.6, 2.3e6 evaluations, in
/// 0.098 s). Only their ratio matters to the choice.
const ZONAL_SECONDS_PER_UNIT: f64 = 5.6e-9;
const ANGULAR_SECONDS_PER_EVALUATION: f64 = 4.3e-8;

/// The angular path's options: the lobe truncated at ε = 1e-4, source texels at most 1/256 of
/// the lobe's equivalent solid angle (about 1/16 of its width): 0.07–0.19 % RMS on Grace in
/// `docs/ibl-building-blocks.md`, the zonal path's accuracy, where the module's default (1/64)
/// measured up to 0.9 % RMS at r = 1 on the shared probes.
pub const ANGULAR_OPTIONS: AngularOptions = AngularOptions { epsilon: 1e-4, texel_ratio: 1.0 / 256.0 };

/// Estimated seconds (one core) of the two exact methods for one level.
pub fn estimate_costs(source: &LatLongSource, lobe: &SplitSumLobe, size: usize, base_size: usize) -> Costs {
    let zonal = ZONAL_SECONDS_PER_UNIT * source.passes(lobe).iter().map(|p| p.cost()).sum::<f64>();
    // Angular ([`ANGULAR_OPTIONS`]): 6n² output texels, each summing the source texels in its cone.
    let options = ANGULAR_OPTIONS;
    let cone = lobe.cone_angle(options.epsilon);
    let source = angular_source_size(lobe, base_size);
    let source_texel = 4.0 * std::f64::consts::PI / (6.0 * (source * source) as f64);
    let in_cone = 2.0 * std::f64::consts::PI * (1.0 - cone.cos()) / source_texel;
    Costs { zonal, angular: ANGULAR_SECONDS_PER_EVALUATION * 6.0 * (size * size) as f64 * in_cone }
}

/// The cube pyramid level the angular prefilter reads for a lobe ([`ANGULAR_OPTIONS`]): the coarsest whose
/// face-centre texel, (2/n)², is within the budget of `AngularPrefilter::source_level`.
fn angular_source_size(lobe: &SplitSumLobe, base_size: usize) -> usize {
    let budget = ANGULAR_OPTIONS.texel_ratio * lobe.equivalent_solid_angle();
    let mut source = base_size;
    while source > 1 && (4.0 / ((source / 2) * (source / 2)) as f64) <= budget {
        source /= 2;
    }
    source
}

/// The cheaper exact method by [`estimate_costs`].
pub fn choose_method(costs: &Costs) -> Method {
    if costs.angular < costs.zonal {
        Method::Angular
    } else {
        Method::Zonal
    }
}

/// The working lat-long map: the input (a lat-long is used as it is, not copied unless it is
/// clamped; other layouts are resampled to 4n × 2n with 2 × 2 supersampling, n the output face
/// size), clamped if asked.
fn working_latlong<'a>(config: &Config, env: &'a EnvMap) -> Result<Cow<'a, EnvMap>, Error> {
    let mut latlong = if env.layout() == Layout::LatLong {
        Cow::Borrowed(env)
    } else {
        Cow::Owned(envmap::resample(env, Layout::LatLong, 4 * config.size, 2 * config.size, 2)?)
    };
    if let Some(max) = config.clamp {
        for img in latlong.to_mut().images_mut() {
            for p in &mut img.pixels {
                for v in p.iter_mut() {
                    *v = v.min(max as f32);
                }
            }
        }
    }
    Ok(latlong)
}

/// One prefiltered level and how it was made.
struct Baked {
    cube: CubeMap,
    level: Level,
}

/// The split-sum level of roughness r > 0 and face size n.
fn bake_level(
    config: &Config,
    latlong: &LatLongSource,
    base: &CubeMap,
    (k, size, r): (usize, usize, f64),
    progress: &dyn Progress,
) -> Result<Baked, Error> {
    let start = Instant::now();
    let env_from_cube = config.world_from_prtkit().transpose();
    let lobe = SplitSumLobe::new(r)?;
    let costs = estimate_costs(latlong, &lobe, size, base.size());
    let method = match config.method {
        MethodChoice::Auto => choose_method(&costs),
        MethodChoice::Zonal => Method::Zonal,
        MethodChoice::Angular => Method::Angular,
    };
    let (cube, source, rule) = match method {
        Method::Angular => {
            // The pyramid from the level it reads down: the finer levels would only cost setup.
            let mut source = base.clone();
            while source.size() > angular_source_size(&lobe, base.size()) {
                source = source.downsample()?;
            }
            let pre = AngularPrefilter::new(CubeMipChain::pyramid(source, 1)?)?;
            let (cube, src) = pre.prefilter(size, r, &ANGULAR_OPTIONS, progress)?;
            (cube, format!("cube {0}x{0}", src.source_size), None)
        }
        _ => {
            let filtered: FilteredSphere = latlong.filter(&lobe, progress)?;
            let cube = CubeMap::from_fn(size, |d| filtered.sample(env_from_cube * d))?;
            (cube, filtered.source, Some(filtered.rule_subsamples))
        }
    };
    let level = Level {
        rule_subsamples: rule,
        estimated_cost: Some(costs),
        seconds: start.elapsed().as_secs_f64(),
        ..unmeasured(k, size, r, method, source)
    };
    Ok(Baked { cube, level })
}

/// A level's manifest entry before it is measured.
fn unmeasured(level: usize, size: usize, roughness: f64, method: Method, source: String) -> Level {
    Level {
        level,
        size,
        roughness,
        method: method.name().into(),
        order: None,
        source,
        rule_subsamples: None,
        estimated_cost: None,
        max_rel_error: None,
        rms_rel_error: None,
        reference_bound: None,
        samples: 0,
        min_value: 0.0,
        seconds: 0.0,
    }
}

/// The cubes of a bake and the seconds each part took.
struct Cubes {
    /// The specular levels, largest first.
    specular: Vec<Baked>,
    irradiance: Baked,
    specular_seconds: f64,
    irradiance_seconds: f64,
}

/// The specular chain and the irradiance cube of the working lat-long map.
fn bake_cubes(
    config: &Config,
    latlong: &EnvMap,
    source: &LatLongSource,
    progress: &dyn Progress,
) -> Result<Cubes, Error> {
    // Level 0: the environment resampled (2 × 2 lookups per texel, a box over its footprint).
    let t_spec = Instant::now();
    let base = CubeMap::resample(latlong, config.size, 2, config.world_from_prtkit().transpose())?;
    let image = latlong.image();
    let resampled = format!("{} {}x{}", latlong.layout().name(), image.width, image.height);
    let level = Level {
        seconds: t_spec.elapsed().as_secs_f64(),
        ..unmeasured(0, config.size, 0.0, Method::Resample, resampled)
    };
    let mut specular = vec![Baked { cube: base.clone(), level }];
    for level in config.filtered_levels() {
        specular.push(bake_level(config, source, &base, level, progress)?);
    }
    let specular_seconds = t_spec.elapsed().as_secs_f64();
    let (irradiance, irradiance_seconds) =
        timed(|| bake_level(config, source, &base, (0, config.irradiance_size, IRRADIANCE_ROUGHNESS), progress));
    Ok(Cubes { specular, irradiance: irradiance?, specular_seconds, irradiance_seconds })
}

/// The reference the levels with r > 0 are measured against and its values at their sampled
/// texels (`samples` > 0): none of it needs the levels themselves, so it is summed beside the
/// bake. One lobe rule serves every level of a roughness (the last level and the irradiance
/// share r = 1).
fn expect(config: &Config, latlong: &EnvMap) -> Result<Option<Expectation>, Error> {
    if config.samples == 0 {
        return Ok(None);
    }
    let reference = Reference::new(latlong)?;
    let measured: Vec<(f64, usize)> = config
        .filtered_levels()
        .map(|(_, size, r)| (r, size))
        .chain([(IRRADIANCE_ROUGHNESS, config.irradiance_size)])
        .collect();
    let mut roughness: Vec<f64> = measured.iter().map(|&(r, _)| r).collect();
    roughness.sort_by(f64::total_cmp);
    roughness.dedup();
    let env_from_cube = config.world_from_prtkit().transpose();
    let expected = roughness
        .par_iter()
        .map(|&r| {
            let sizes: Vec<usize> = measured.iter().filter(|l| l.0 == r).map(|l| l.1).collect();
            let expected = reference.expect(&SplitSumLobe::new(r)?, env_from_cube, config.samples, &sizes);
            Ok(expected.into_iter().map(|e| (r, e)).collect::<Vec<_>>())
        })
        .collect::<Result<Vec<_>, Error>>()?;
    let against = reference.is_bounded().then(|| reference.describe());
    Ok(Some(Expectation {
        expected: expected.into_iter().flatten().collect(),
        bounded: reference.is_bounded(),
        against,
    }))
}

/// What [`expect`] finds: per roughness and face size, the reference at the sampled texels.
struct Expectation {
    expected: Vec<(f64, Expected)>,
    /// Whether the reference may differ from the texel-by-texel sum over the input (then each
    /// level records the bound).
    bounded: bool,
    /// What the levels are measured against, when it is not the texel-by-texel sum.
    against: Option<String>,
}

/// Records every level's most negative texel and, with the reference's values ([`expect`]),
/// the error of the levels with r > 0. Returns what they were measured against when it is not
/// the texel-by-texel sum over the input.
fn measure(expectation: Option<Expectation>, levels: Vec<&mut Baked>) -> Option<String> {
    let mut levels = levels;
    for b in levels.iter_mut() {
        b.level.min_value = b.cube.texels().iter().fold(0.0f32, |m, &v| m.min(v)) as f64;
    }
    let expectation = expectation?;
    for b in levels {
        let (r, size) = (b.level.roughness, b.level.size);
        let Some((_, expected)) = expectation.expected.iter().find(|(er, e)| *er == r && e.size() == size) else {
            continue; // r = 0: the resampled input, not a lobe's integral
        };
        let m = expected.measure(&b.cube);
        b.level.max_rel_error = Some(m.max_rel_error);
        b.level.rms_rel_error = Some(m.rms_rel_error);
        b.level.reference_bound = expectation.bounded.then_some(m.reference_bound);
        b.level.samples = m.samples;
    }
    expectation.against
}

/// The irradiance cube is the split-sum level of r = 1: GGX's D is 1/π there, so the lobe is the
/// clamped cosine over π and the level is E/π.
const IRRADIANCE_ROUGHNESS: f64 = 1.0;

/// What a texel of the irradiance cube and the SH snippets' result are.
const IRRADIANCE_SCALE: &str = "E(n)/pi: the radiance a white Lambertian surface reflects (multiply by the albedo)";

/// What a level of the specular chain holds.
const SPECULAR_LOBE: &str =
    "split-sum GGX (Karis 2013): N = V = R, weights D(h) max(N.L, 0), normalized; perceptual roughness r, alpha = r^2";

/// Where a value of the DFG table is and how a shader combines it, by variant.
fn dfg_layout(variant: DfgVariant) -> &'static str {
    match variant {
        DfgVariant::ScaleBias => "texel (row j, column i) at n.v = (i+0.5)/N, r = (j+0.5)/N, row 0 smoothest; sample uv = (n.v, r), clamp, linear; (x, y) = (A, B): specular = prefiltered * (F0 * x + y)",
        DfgVariant::MultiScatter => "texel (row j, column i) at n.v = (i+0.5)/N, r = (j+0.5)/N, row 0 smoothest; sample uv = (n.v, r), clamp, linear; (x, y) = (B, A + B), Filament's DFV_Multiscatter: specular = prefiltered * mix(x, y, F0) * (1 + F0 (1/y - 1))",
    }
}

/// The manifest's body: every file of DIR, what it holds and how each level was made.
fn manifest_body(
    config: &Config,
    env: &EnvMap,
    source_hash: String,
    cubes: (Vec<Level>, Level),
    dfg: &DfgTable,
    measured_against: Option<String>,
    timings: Timings,
) -> IblBody {
    let ext = config.container.name();
    let (levels, irradiance) = cubes;
    IblBody {
        source: config.source.clone(),
        source_hash: Some(source_hash),
        measured_against,
        frame: config.frame(env.orientation()),
        specular: manifest::Specular {
            file: format!("specular.{ext}"),
            container: ext.into(),
            format: config.format.name().into(),
            roughness_map: config.roughness_map.name().into(),
            roughness_formula: config.roughness_map.formula().into(),
            lobe: SPECULAR_LOBE.into(),
            levels,
        },
        irradiance: manifest::Irradiance {
            file: format!("irradiance.{ext}"),
            size: config.irradiance_size,
            format: config.format.name().into(),
            scale: IRRADIANCE_SCALE.into(),
            level: irradiance,
        },
        sh: manifest::ShFiles {
            file: "sh.json".into(),
            shaders: vec!["sh.glsl".into(), "sh.hlsl".into(), "sh.wgsl".into()],
            scale: IRRADIANCE_SCALE.into(),
        },
        dfg: manifest::Dfg {
            file: format!("dfg.{ext}"),
            size: dfg.size(),
            variant: match config.dfg {
                DfgVariant::ScaleBias => "scale-bias".into(),
                DfgVariant::MultiScatter => "multiscatter".into(),
            },
            format: config.dfg_format().name().into(),
            layout: dfg_layout(config.dfg).into(),
        },
        timings,
    }
}

/// The `prtkit.ibl-sh` body.
fn sh_body(config: &Config, input: Orientation, sh: &IrradianceSh) -> ShBody {
    ShBody {
        frame: config.frame(input),
        basis: ["1", "y", "z", "x", "x*y", "y*z", "3*z*z - 1", "x*z", "x*x - y*y"]
            .iter()
            .map(|s| s.to_string())
            .collect(),
        scale: IRRADIANCE_SCALE.into(),
        coefficients: sh.shader.to_vec(),
        radiance: sh.radiance.rgb.clone(),
    }
}

/// A document of the bake: its conventions name the frame the files are in (the output frame,
/// not prtkit's) and how the input was turned on reading.
fn document<T: serde::Serialize>(
    format: &str,
    provenance: Provenance,
    body: T,
    frame: &str,
    input: Orientation,
) -> Document<T> {
    let mut document = Document::new(format, manifest::VERSION, provenance, body);
    document.conventions.frame = frame.to_string();
    document.with_input_orientation(input.describe())
}

/// `f`'s result and the seconds it took.
fn timed<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let start = Instant::now();
    (f(), start.elapsed().as_secs_f64())
}

/// Runs `ibl` on `env` (any layout, prtkit's frame).
pub fn run(config: &Config, env: &EnvMap, progress: &dyn Progress) -> Result<Output, Error> {
    config.check()?;
    let input_texels = env.images().iter().map(|i| (i.width * i.height) as u64).sum();
    crate::limits::check_memory("the bake", config.planned_bytes(input_texels))?;
    let t0 = Instant::now();
    let mut timings = Timings::default();
    let latlong = working_latlong(config, env)?;
    let source = LatLongSource::new(latlong.image());
    timings.prepare = t0.elapsed().as_secs_f64();

    // The DFG table depends on nothing else, the SH and the input's fingerprint only on the
    // input: they run beside the cubes, and so does the measurement's reference, which needs only
    // the input: it fills the cores the bake's narrower steps leave idle.
    let (((((dfg, dfg_seconds), source_hash), (sh, sh_seconds)), cubes), (expectation, reference_seconds)) =
        rayon::join(
            || {
                rayon::join(
                    || {
                        rayon::join(
                            || (timed(|| DfgTable::new(config.dfg_size, config.dfg)), env.content_hash()),
                            || timed(|| IrradianceSh::project(&latlong, config.world_from_prtkit())),
                        )
                    },
                    || bake_cubes(config, &latlong, &source, progress),
                )
            },
            || timed(|| expect(config, &latlong)),
        );
    let (dfg, sh, expectation) = (dfg?, sh?, expectation?);
    let Cubes { mut specular, mut irradiance, specular_seconds, irradiance_seconds } = cubes?;
    timings.dfg = dfg_seconds;
    timings.specular = specular_seconds;
    timings.irradiance = irradiance_seconds + sh_seconds;
    timings.reference = reference_seconds;
    timings.bake = t0.elapsed().as_secs_f64();

    let levels = specular.iter_mut().chain([&mut irradiance]).collect();
    let (measured_against, measure_seconds) = timed(|| measure(expectation, levels));
    timings.measure = measure_seconds;

    // The levels move into the chain: the largest bakes hold one copy of their cubes.
    let (cubes, levels): (Vec<CubeMap>, Vec<Level>) = specular.into_iter().map(|b| (b.cube, b.level)).unzip();
    let body = manifest_body(config, env, source_hash, (levels, irradiance.level), &dfg, measured_against, timings);
    let (frame, input) = (config.frame_words(env.orientation()), env.orientation());
    let provenance = Provenance::new("ibl", &config.args, vec![config.source.clone()]);
    let sh_document = document(manifest::SH_FORMAT, provenance.clone(), sh_body(config, input, &sh), &frame, input);
    Ok(Output {
        document: document(manifest::FORMAT, provenance, body, &frame, input),
        sh_document,
        sh,
        specular: CubeMipChain::new(cubes)?,
        irradiance: irradiance.cube,
        dfg,
        container: config.container,
        format: config.format,
        dfg_format: config.dfg_format(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn roughness_maps() {
        assert_eq!(RoughnessMap::Linear.roughness(2, 6), 0.4);
        // Filament: lod = r(2 − r) inverted.
        for k in 0..6 {
            let r = RoughnessMap::Filament.roughness(k, 6);
            assert!((r * (2.0 - r) - k as f64 / 5.0).abs() < 1e-12);
        }
        assert_eq!(RoughnessMap::Filament.roughness(5, 6), 1.0);
    }

    #[test]
    fn frame_matrix_is_the_gltf_rotation_then_the_turn() {
        let c = Config::default();
        assert_eq!(c.world_from_prtkit(), WORLD_FROM_PRTKIT);
        let turned = Config { rotate_degrees: 90.0, up: Up::Z, ..Config::default() };
        assert!((turned.world_from_prtkit() * DVec3::X - DVec3::Y).length() < 1e-12);
        let mirrored = Config { mirror: true, up: Up::Z, ..Config::default() };
        assert_eq!(mirrored.world_from_prtkit() * DVec3::Y, -DVec3::Y);
    }

    /// The errors the bake records, whose reference is summed beside it once per roughness,
    /// are those of measuring each finished level on its own: each level is compared with the
    /// samples of its own size and lobe (the last level, 4², and the 32² irradiance share r = 1).
    #[test]
    fn errors_summed_beside_the_bake_are_each_levels_own() {
        let grid = crate::sphere::LatLong::new(64, 32);
        let sun = DVec3::new(0.3, -0.5, 0.8).normalize();
        let env = EnvMap::latlong(crate::io::RgbImage::from_fn(64, 32, |x, y| {
            let d = grid.texel_direction(x, y);
            let glow = (-(1.0 - d.dot(sun)) * 40.0).exp() * 20.0;
            [(0.5 + 0.3 * d.x + glow) as f32, (0.4 + glow) as f32, (0.3 + 0.2 * d.z.abs()) as f32]
        }))
        .unwrap();
        let config = Config { size: 32, min_size: 4, irradiance_size: 32, samples: 48, ..Config::default() };
        let out = run(&config, &env, &crate::progress::NoProgress).unwrap();
        let body = &out.document.body;
        let reference = Reference::new(&env).unwrap();
        let env_from_cube = config.world_from_prtkit().transpose();
        let cubes = out.specular.levels().iter().chain([&out.irradiance]);
        let levels = body.specular.levels.iter().chain([&body.irradiance.level]);
        let mut measured = 0;
        for (cube, level) in cubes.zip(levels).filter(|(_, l)| l.roughness > 0.0) {
            let own = reference.measure(cube, &SplitSumLobe::new(level.roughness).unwrap(), env_from_cube, 48);
            assert_eq!(
                (level.max_rel_error, level.rms_rel_error, level.samples),
                (Some(own.max_rel_error), Some(own.rms_rel_error), own.samples),
                "level {} ({}², r = {})",
                level.level,
                level.size,
                level.roughness
            );
            measured += 1;
        }
        assert_eq!(measured, 4, "three levels with r > 0 and the irradiance");
        assert_eq!(body.specular.levels.last().map(|l| (l.size, l.roughness)), Some((4, 1.0)));
    }

    #[test]
    fn bad_sizes_are_refused() {
        assert!(matches!(Config { size: 100, ..Config::default() }.check(), Err(Error::Size { .. })));
        assert!(matches!(Config { min_size: 512, ..Config::default() }.check(), Err(Error::MinSize { .. })));
        assert!(matches!(
            Config { format: TexelFormat::Rg16Float, ..Config::default() }.check(),
            Err(Error::Format(_))
        ));
        assert_eq!(Config::default().levels(), 6);
    }
}
