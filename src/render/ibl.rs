//! Shading from an `ibl` bake as a glTF/PBR engine does (Karis 2013, "Real Shading in Unreal
//! Engine 4"; the glTF Sample Viewer's image-based lighting), for the glTF metallic-roughness
//! material ([`GltfMaterial`]):
//!
//!   specular = prefiltered(R', r) · (F0·A + B),
//!   diffuse  = (1 − m) c · E(n)/π · (1 − (0.04·A + B)),
//!
//! R' the dominant direction ([`dominant_direction`]: R bent towards n as the lobe widens),
//! prefiltered from `specular.ktx2` (trilinear: bilinear in the two levels whose roughness
//! brackets r, linear between them), E/π from `irradiance.ktx2`, (A, B) from `dfg.ktx2` at
//! (n·v, r). The diffuse keeps what the dielectric layer does not reflect: 0.04·A + B is that
//! layer's directional albedo (the single-scattering form of the glTF Sample Viewer).
//! Directions go through the manifest's `world_from_prtkit` before every lookup, so the files are
//! read in the frame they were written in, exactly as an engine would.
//!
//! The ground truth is [`super::reference`] with the same material: the rendering equation
//! integrated over every environment texel. What remains between the two is the split sum itself
//! (the lobe taken at N = V = R, the BRDF's integral split from the lighting's) and the bake's
//! resolution, which is the point of the comparison.

use super::{Hit, Shade};
use crate::brdf::ggx::{GgxError, SplitSumLobe};
use crate::brdf::models::GltfMaterial;
use crate::envmap::EnvMap;
use crate::ibl::cube::CubeMap;
use crate::ibl::dfg::split_sum_terms;
use crate::ibl::manifest::{IblBody, FACE_ORDER, FORMAT, VERSION};
use crate::ibl::reference::{LobeIntegral, Reference};
use crate::io::document::{named_file, read_document, BundleError};
use crate::io::gpu_format::TextureShape;
use crate::io::ktx2::{decode, DecodedTexture};
use crate::sphere::latlong::bilinear_taps;
use glam::{DMat3, DVec3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Errors of reading a bake: the manifest's, or one of the files it names.
pub type IblLoadError = BundleError;

/// The split-sum table: N×N texels of (A, B) at n·v = (i + ½)/N (columns), r = (j + ½)/N (rows).
#[derive(Clone, Debug)]
struct ScaleBias {
    size: usize,
    values: Vec<[f64; 2]>,
}

impl ScaleBias {
    /// (A, B) at (n·v, r), bilinear between texel centres, clamped at the edges.
    fn lookup(&self, n_dot_v: f64, roughness: f64) -> [f64; 2] {
        let n = self.size as f64;
        let mut out = [0.0; 2];
        for (i, w) in bilinear_taps(self.size, self.size, n_dot_v * n - 0.5, roughness * n - 0.5, false) {
            out[0] += w * self.values[i][0];
            out[1] += w * self.values[i][1];
        }
        out
    }
}

/// An `ibl` bake read back from its manifest and files.
#[derive(Clone, Debug)]
pub struct IblBake {
    /// d_out = M d_prtkit: the frame the files are in.
    world_from_prtkit: DMat3,
    /// The specular chain: each level's roughness and cube, largest first.
    specular: Vec<(f64, CubeMap)>,
    /// E/π.
    irradiance: CubeMap,
    dfg: ScaleBias,
    /// The manifest, the map it names as its source and that map's fingerprint (when recorded).
    manifest: PathBuf,
    source: String,
    source_hash: Option<String>,
}

/// A bake given with a map other than the one it was made from.
#[derive(Debug, thiserror::Error)]
#[error(
    "{}: baked from {baked_from} ({baked_hash}), but the environment map given is another ({given_hash}); \
     give the map the bake was made from, read the same way (flipped vertically or not)",
    manifest.display()
)]
pub struct OtherSource {
    /// The bake's manifest.
    pub manifest: PathBuf,
    /// The map the manifest names.
    pub baked_from: String,
    /// Its fingerprint in the manifest.
    pub baked_hash: String,
    /// The given map's fingerprint.
    pub given_hash: String,
}

impl IblBake {
    /// Reads `DIR/ibl.json` and the KTX2 files it names, checking them against it.
    pub fn load(manifest: &Path) -> Result<Self, IblLoadError> {
        crate::io::read::refuse_stdin(manifest, "a bake's ibl.json")?;
        let body = read_document::<IblBody>(manifest, FORMAT, VERSION)?.body;
        let bad = |reason: String| IblLoadError::Document { path: manifest.into(), reason };
        if body.specular.container != "ktx2" {
            return Err(bad(format!(
                "the bake's container is {}; render reads KTX2 bakes (ibl --container ktx2)",
                body.specular.container
            )));
        }
        // Rows as written: d_out = M d_prtkit (checked orthonormal when read).
        let world_from_prtkit = DMat3::from_cols_array_2d(&body.frame.world_from_prtkit).transpose();
        let roughness: Vec<f64> = body.specular.levels.iter().map(|l| l.roughness).collect();

        if body.frame.faces != FACE_ORDER {
            return Err(bad(format!(
                "frame.faces is {:?}; the cube files hold their faces in the order {FACE_ORDER:?}",
                body.frame.faces
            )));
        }
        let specular = read_cube(manifest, &body.specular.file, "specular cube")?;
        let level_sizes: Vec<usize> = body.specular.levels.iter().map(|l| l.size).collect();
        check_described(manifest, &body.specular.file, &specular, &body.specular.format, &level_sizes)?;
        let size = cube_size(&specular);
        let specular = roughness
            .into_iter()
            .zip(&specular.levels)
            .enumerate()
            .map(|(p, (r, texels))| (r, to_cube((size >> p).max(1), texels)))
            .collect();
        let irradiance = read_cube(manifest, &body.irradiance.file, "irradiance cube")?;
        let (described, level) = (&body.irradiance, body.irradiance.level.size);
        check_described(manifest, &described.file, &irradiance, &described.format, &[described.size])?;
        if level != described.size {
            return Err(bad(format!("irradiance.size is {}, its level's size {level}", described.size)));
        }
        let irradiance = to_cube(cube_size(&irradiance), &irradiance.levels[0]);

        let dfg_file = named_file(manifest, &body.dfg.file);
        let dfg = read_texture(manifest, &body.dfg.file, "DFG table")?;
        check_described(manifest, &body.dfg.file, &dfg, &body.dfg.format, &[body.dfg.size])?;
        let TextureShape::Texture2d { width, height } = dfg.shape else {
            return Err(mismatch(manifest, &body.dfg.file, "a cube map, not a 2-D table".into()));
        };
        if width != height || dfg.format.channels() != 2 {
            return Err(IblLoadError::Mismatch {
                exr: dfg_file,
                doc: manifest.into(),
                reason: format!(
                    "a {width}×{height} table of {} channels; the DFG table is square RG",
                    dfg.format.channels()
                ),
            });
        }
        let pairs = dfg.levels[0].chunks_exact(2).map(|p| [p[0] as f64, p[1] as f64]);
        // (A, B) from either layout (`ibl::dfg`): multiscatter stores (B, A + B).
        let values = match body.dfg.variant.as_str() {
            "scale-bias" => pairs.collect(),
            "multiscatter" => pairs.map(|[b, e]| [e - b, b]).collect(),
            v => return Err(bad(format!("unknown DFG variant {v:?} (scale-bias or multiscatter)"))),
        };
        Ok(IblBake {
            world_from_prtkit,
            specular,
            irradiance,
            dfg: ScaleBias { size: width, values },
            manifest: manifest.into(),
            source: body.source,
            source_hash: body.source_hash,
        })
    }

    /// Whether the bake was made from `env` as read (its fingerprint, `EnvMap::content_hash`):
    /// `Ok(false)` when the manifest predates fingerprints and cannot tell.
    pub fn check_source(&self, env: &EnvMap) -> Result<bool, OtherSource> {
        let Some(baked_hash) = &self.source_hash else { return Ok(false) };
        let given_hash = env.content_hash();
        if *baked_hash != given_hash {
            return Err(OtherSource {
                manifest: self.manifest.clone(),
                baked_from: self.source.clone(),
                baked_hash: baked_hash.clone(),
                given_hash,
            });
        }
        Ok(true)
    }

    /// Face size of the specular chain's level 0.
    pub fn size(&self) -> usize {
        self.specular[0].1.size()
    }
}

fn mismatch(manifest: &Path, file: &str, reason: String) -> IblLoadError {
    IblLoadError::Mismatch { exr: named_file(manifest, file), doc: manifest.into(), reason }
}

fn read_texture(manifest: &Path, file: &str, what: &'static str) -> Result<DecodedTexture, IblLoadError> {
    let path: PathBuf = named_file(manifest, file);
    let bytes =
        crate::io::read_bytes(&path, "KTX2", crate::limits::max_file_bytes(), crate::io::ktx2::check_identifier)
            .map_err(|error| IblLoadError::Named { doc: manifest.into(), what, error })?;
    decode(&bytes).map_err(|e| mismatch(manifest, file, e.to_string()))
}

fn read_cube(manifest: &Path, file: &str, what: &'static str) -> Result<DecodedTexture, IblLoadError> {
    let texture = read_texture(manifest, file, what)?;
    if !matches!(texture.shape, TextureShape::Cube { .. }) || texture.format.channels() < 3 {
        return Err(mismatch(manifest, file, format!("the {what} must be an RGB(A) cube map")));
    }
    Ok(texture)
}

/// Checks a file read back against what the manifest says of it: its format, and its levels'
/// sizes (`sizes`, largest first: one per level, each half the one before). A file that
/// contradicts its manifest (another bake's, or the specular cube in place of the irradiance)
/// would otherwise be rendered as if it were what the manifest says.
fn check_described(
    manifest: &Path,
    file: &str,
    texture: &DecodedTexture,
    format: &str,
    sizes: &[usize],
) -> Result<(), IblLoadError> {
    let differs = |reason: String| Err(mismatch(manifest, file, reason));
    if texture.format.name() != format {
        return differs(format!("the file is {}, the manifest says {format}", texture.format.name()));
    }
    let size = texture.shape.dimensions().0;
    let file_sizes: Vec<usize> = (0..texture.levels.len()).map(|p| (size >> p).max(1)).collect();
    if file_sizes != sizes {
        return differs(format!("the file's levels are {file_sizes:?} texels wide, the manifest says {sizes:?}"));
    }
    Ok(())
}

fn cube_size(texture: &DecodedTexture) -> usize {
    texture.shape.dimensions().0
}

/// A decoded level (3 or 4 channels per texel) as an RGB cube.
fn to_cube(size: usize, texels: &[f32]) -> CubeMap {
    let channels = texels.len() / (6 * size * size);
    let mut cube = CubeMap::new(size).expect("a decoded cube's size is valid");
    for (out, t) in cube.texels_mut().chunks_exact_mut(3).zip(texels.chunks_exact(channels)) {
        out.copy_from_slice(&t[..3]);
    }
    cube
}

/// What the split sum reads: the prefiltered lobe, the irradiance and the (A, B) pair. The
/// bake's files are one source ([`IblBake`]), the exact integrals another ([`ExactSplitSum`]):
/// the difference between the two is the bake's error alone.
pub trait SplitSumLighting: Sync {
    /// The prefiltered radiance about the prtkit-frame direction `r` for `roughness`.
    fn prefiltered(&self, r: DVec3, roughness: f64) -> [f64; 3];
    /// E(n)/π at the prtkit-frame normal `n`.
    fn irradiance(&self, n: DVec3) -> [f64; 3];
    /// The split-sum (A, B) at (n·v, r).
    fn scale_bias(&self, n_dot_v: f64, roughness: f64) -> [f64; 2];
}

impl SplitSumLighting for IblBake {
    /// Bilinear in the two levels whose roughness brackets `roughness`, linear in roughness
    /// between them (what `textureLod` does with lod = the level position of r).
    fn prefiltered(&self, r: DVec3, roughness: f64) -> [f64; 3] {
        let d = self.world_from_prtkit * r;
        let k = self.specular.partition_point(|(rk, _)| *rk <= roughness);
        let sample = |i: usize| self.specular[i].1.lookup_bilinear(d).map(f64::from);
        if k == 0 {
            return sample(0);
        }
        if k == self.specular.len() {
            return sample(k - 1);
        }
        let (r0, r1) = (self.specular[k - 1].0, self.specular[k].0);
        let f = (roughness - r0) / (r1 - r0);
        let (a, b) = (sample(k - 1), sample(k));
        [0, 1, 2].map(|c| a[c] + f * (b[c] - a[c]))
    }

    fn irradiance(&self, n: DVec3) -> [f64; 3] {
        self.irradiance.lookup_bilinear(self.world_from_prtkit * n).map(f64::from)
    }

    fn scale_bias(&self, n_dot_v: f64, roughness: f64) -> [f64; 2] {
        self.dfg.lookup(n_dot_v, roughness)
    }
}

/// One split-sum lobe's exact integral over an environment, B(R) by `ibl`'s angular reference
/// ([`crate::ibl::reference`]), remembered per direction: the renders of a grid ask for the same
/// directions again (every metalness of one roughness, the irradiance of every cell), and each
/// sum covers a hemisphere.
pub struct ExactLobe<'a> {
    integral: LobeIntegral<'a>,
    memo: Mutex<HashMap<[u64; 3], [f64; 3]>>,
}

impl<'a> ExactLobe<'a> {
    /// The lobe of perceptual roughness `roughness` over `reference`'s environment. At r = 1 GGX
    /// has D = 1/π, so the split-sum kernel is the clamped cosine over π and B(n) is E(n)/π.
    pub fn new(reference: &Reference<'a>, roughness: f64) -> Result<Self, GgxError> {
        let lobe = SplitSumLobe::new(roughness)?;
        Ok(ExactLobe { integral: reference.lobe(&lobe), memo: Mutex::default() })
    }

    /// B at the prtkit-frame direction `d`.
    pub fn at(&self, d: DVec3) -> [f64; 3] {
        let key = d.to_array().map(f64::to_bits);
        if let Some(v) = self.memo.lock().map_or(None, |m| m.get(&key).copied()) {
            return v;
        }
        let v = self.integral.at(d);
        if let Ok(mut m) = self.memo.lock() {
            m.insert(key, v);
        }
        v
    }
}

/// The split sum's own integrals, exact: the prefiltered lobe and the irradiance
/// ([`ExactLobe`]), (A, B) by [`crate::ibl::dfg::split_sum_terms`]' quadrature.
pub struct ExactSplitSum<'a> {
    /// The lobe of the material's roughness.
    pub specular: &'a ExactLobe<'a>,
    /// The lobe of roughness 1: E/π.
    pub irradiance: &'a ExactLobe<'a>,
}

impl SplitSumLighting for ExactSplitSum<'_> {
    fn prefiltered(&self, r: DVec3, _roughness: f64) -> [f64; 3] {
        self.specular.at(r)
    }

    fn irradiance(&self, n: DVec3) -> [f64; 3] {
        self.irradiance.at(n)
    }

    fn scale_bias(&self, n_dot_v: f64, roughness: f64) -> [f64; 2] {
        split_sum_terms(n_dot_v, roughness).map_or([0.0; 2], |t| [t.scale, t.bias])
    }
}

/// Where a split-sum engine reads the prefiltered lobe: R bent towards n as the lobe widens
/// (Lagarde & de Rousiers 2014, "Moving Frostbite to PBR", §4.9.3, with α = r²):
/// lerp(n, R, s), s = (1 − α)(√(1 − α) + α). The lobe of a rough BRDF is centred nearer the
/// normal than R is (off-specular peak and the n·l factor); Filament bends R the same way. On
/// Grace, rough metals (r ≥ 0.6) go from 35–54 % to 10–20 % error against the reference.
pub fn dominant_direction(n: DVec3, wo: DVec3, roughness: f64) -> DVec3 {
    let alpha = roughness * roughness;
    let s = (1.0 - alpha) * ((1.0 - alpha).sqrt() + alpha);
    (n + s * (super::reflect(wo, n) - n)).normalize_or(n)
}

/// The split-sum shader of one material.
pub struct SplitSum<'a> {
    lighting: &'a dyn SplitSumLighting,
    material: GltfMaterial,
}

impl<'a> SplitSum<'a> {
    /// Shades `material` from `lighting` (a bake, or the exact integrals).
    pub fn new(lighting: &'a dyn SplitSumLighting, material: GltfMaterial) -> Self {
        SplitSum { lighting, material }
    }
}

impl Shade for SplitSum<'_> {
    fn shade(&self, hit: &Hit, wo: DVec3) -> [f64; 3] {
        let (n, m) = (hit.n, &self.material);
        let roughness = m.specular.roughness();
        // The table starts at n·v = 1/(2N); engines clamp n·v away from 0 the same way.
        let n_dot_v = n.dot(wo).clamp(1e-4, 1.0);
        let [a, b] = self.lighting.scale_bias(n_dot_v, roughness);
        let prefiltered = self.lighting.prefiltered(dominant_direction(n, wo, roughness), roughness);
        let irradiance = self.lighting.irradiance(n);
        let (f0, kd) = (m.f0(), m.diffuse_colour());
        let transmitted = 1.0 - (GltfMaterial::DIELECTRIC_F0 * a + b);
        [0, 1, 2].map(|c| prefiltered[c] * (f0[c] * a + b) + kd[c] * irradiance[c] * transmitted)
    }
}
