//! The in-out BRDF factorization and its term counts (Mahajan, Tseng & Ramamoorthi 2008, "An
//! Analysis of the In-Out BRDF Factorization for View-Dependent Relighting").
//!
//! - [`grid`]: the equal-solid-angle (cos θ, φ) grid of the BRDF matrix;
//! - [`svd`]: the matrix and its SVD, dense or block-circulant (FFT over φ);
//! - [`energy`]: energy curves, K at an energy fraction, reconstruction error;
//! - [`predict`]: the paper's closed-form predictions of K, from 1-D transforms;
//! - [`count`]: predicted versus measured K for a list of materials, and the CI check;
//! - [`document`]: the `prtkit.factor` document and the factor file render reads;
//! - [`maps`], [`plot`]: pictures of the factors and of the counts.

pub mod channel;
pub mod count;
pub mod document;
pub mod energy;
pub mod grid;
pub mod manifest;
pub mod maps;
pub mod plot;
pub mod predict;
pub mod stage;
pub mod svd;

pub use channel::Channel;
pub use grid::{CellSamples, Domain, Grid};
pub use svd::{factor, FactorError, Factorization, Method, Sampling};

#[cfg(test)]
mod tests;
