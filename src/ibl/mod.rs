//! Image-based lighting for glTF/PBR engines: the building blocks of the `ibl` stage.
//!
//! - [`ggx`]: the GGX distribution, the height-correlated Smith visibility and the split-sum
//!   prefilter lobe with its zonal SH coefficients (Karis 2013; Heitz 2014; Walter et al. 2007).
//! - [`dfg`]: the split-sum scale/bias table (and Filament's multiple-scattering variant),
//!   integrated by deterministic quadrature.
//! - [`cube`]: cube maps in the Vulkan/KTX face order and orientation, texel geometry, mip chains
//!   and the glTF (+Y up) ↔ prtkit (+Z up) frame change.
//! - [`angular`]: the lobe-truncated angular GGX prefilter of a cube level from a mip pyramid,
//!   its exact reference and the per-level error measurement.
//!
//! `docs/ibl-building-blocks.md` states the conventions and the measured speeds and accuracies.

pub mod angular;
pub mod cube;
pub mod dfg;
pub mod ggx;
