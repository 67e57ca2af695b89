//! Image-based lighting for glTF/PBR engines: the building blocks of the `ibl` stage, on the GGX
//! of [`crate::brdf::ggx`].
//!
//! - [`dfg`]: the split-sum scale/bias table (and Filament's multiple-scattering variant),
//!   integrated by deterministic quadrature.
//! - [`cube`]: cube maps in the Vulkan/KTX face order and orientation, texel geometry, mip chains
//!   and the glTF (+Y up) ↔ prtkit (+Z up) frame change.
//! - [`angular`]: the lobe-truncated angular GGX prefilter of a cube level from a mip pyramid,
//!   its exact reference and the per-level error measurement.
//! - [`frequency`]: the zonal (frequency-space) path of a level: row-pair FFTs on a lat-long
//!   grid matched to the lobe, read back by direction.
//! - [`reference`](mod@reference): the angular integral of the input every level is measured against.
//! - [`sh_irradiance`]: order-2 SH irradiance in the output frame and its shader snippets.
//! - [`manifest`]: the `prtkit.ibl` manifest and the `prtkit.ibl-sh` document.
//! - [`stage`]: the `ibl` stage as one library call.
//!
//! `docs/ibl-building-blocks.md` states the conventions and the measured speeds and accuracies.

pub mod angular;
pub mod cube;
pub mod dfg;
pub mod frequency;
pub mod manifest;
pub mod reference;
pub mod sh_irradiance;
pub mod stage;
