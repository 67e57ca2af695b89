//! Precomputed radiance transfer for meshes (Sloan, Kautz & Snyder 2002, "Precomputed Radiance
//! Transfer for Real-Time Rendering in Dynamic, Low-Frequency Lighting Environments").
//!
//! A diffuse surface point x under distant lighting L(ω) reflects
//! B(x) = (ρ/π) ∫ L(ω) V(x, ω) max(n·ω, 0) dω (Sloan et al. 2002, eq. 2, shadowed). Projecting
//! the lighting onto SH, L(ω) = Σ_i L_i Y_i(ω), turns the integral into a dot product
//! B(x) = Σ_i T_i(x) L_i with the *transfer vector*
//!
//! T_i(x) = (ρ/π) ∫ V(x, ω) max(n·ω, 0) Y_i(ω) dω            (Sloan et al. 2002, eq. 7–8),
//!
//! which depends on the geometry only, so it is baked once and relit at run time for any
//! low-frequency lighting. This module computes T per vertex: [`diffuse`] holds the two
//! integrators (exact quadrature without visibility, stratified rays with it), [`directions`]
//! the stratified ray directions, [`visibility`] the BVH the rays are cast through,
//! [`interreflect`] the bounces, [`shaders`] the run-time dot product and SH rotation (GLSL,
//! HLSL, WGSL), [`lightmap`] the same diffuse transfer per texel of a UV set, [`cpca`] and
//! [`quantize`] the compressed and quantized storage, [`order`] the SH order an energy fraction
//! needs, [`albedo`] the grey or coloured albedo folded in, [`jobs`] a bake split into jobs whose
//! parts join into one run's outputs, and [`stage`] the `transfer` stage.

pub mod albedo;
pub mod atlas;
pub mod cpca;
pub mod diffuse;
pub mod directions;
pub mod glossy;
pub mod interreflect;
pub mod jobs;
pub mod lightmap;
pub mod order;
pub mod quantize;
pub mod shaders;
pub mod stage;
pub mod visibility;
