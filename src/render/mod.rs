//! Rendering the bakes against ground truth: a look-at camera, an analytic sphere or an OBJ
//! mesh in front of the environment, and five shading modes:
//!
//! - [`irradiance`]: Lambert from SH lighting, B = (a/π) Σ Â_l L_lm Y_lm(n) (R&H 2001 eq. 8–9);
//! - [`reflection`]: SHRMs, global for a distant viewer (R&H 2002 eq. 12) or local per pixel (eq. 6);
//! - [`factored`]: the in-out factorization, B = Σ_k σ_k h_k(ω_o) Σ_i T_k(ω_i) L(ω_i) with
//!   T_k = V g_k (n·ω_i) (Mahajan et al. 2008, eq. 3–4);
//! - [`ibl`]: the split sum from an `ibl` bake's files, as a glTF/PBR engine shades;
//! - [`reference`](mod@reference): direct integration of environment × BRDF × cosine over every env texel.
//!
//! [`grid`] lays the `ibl` shading out as a roughness × metalness grid above its references.
//!
//! [`crate::metrics`] compares renders, [`panel`] lays them out with labels. `docs/render.md` is the
//! user guide.

pub mod camera;
pub mod factored;
pub mod font;
pub mod frame;
pub mod grid;
pub mod ibl;
pub mod irradiance;
pub mod panel;
mod plan;
pub mod reference;
pub mod reflection;
pub mod scene;
pub mod stage;
pub mod transfer;

pub use camera::Camera;
pub use frame::{render, render_turned, Frame, Shade, Sum};
pub use scene::{Hit, Scene};

use glam::DVec3;

/// Mirror reflection of the view direction `wo` (towards the viewer) about `n`.
pub fn reflect(wo: DVec3, n: DVec3) -> DVec3 {
    2.0 * n.dot(wo) * n - wo
}
