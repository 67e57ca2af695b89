//! The MERL measured-BRDF format (Matusik, Pfister, Brand & McMillan 2003, "A Data-Driven
//! Reflectance Model"), read with the lookup convention of MERL's own `BRDFRead.cpp`, described
//! (not copied) in `docs/brdf-specs.md`:
//!
//! - header: 3 × int32 little-endian, (90, 90, 180); the product must be 90·90·360/2 = 1,458,000;
//! - payload: 3 × 1,458,000 float64 little-endian, channel-major (all R, then G, then B);
//! - index: i_φd + 180·i_θd + 180·90·i_θh; value = raw × scale with scales (1, 1.15, 1.66)/1500;
//! - raw values < 0 mark configurations that were not measured: missing, evaluated as 0;
//! - lookup: floor and clamp, no interpolation; θ_h uses the square-root mapping
//!   i = ⌊√(θ_h/(π/2)·90·90)⌋ (entry i sits at θ_h = (i/90)²·π/2); φ_d < 0 is folded by +π.

use super::halfdiff::{self, HalfDiff};
use super::BrdfError;
use crate::io::IoError;
use glam::DVec3;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

/// Samples along θ_h.
pub const RES_THETA_H: usize = 90;
/// Samples along θ_d.
pub const RES_THETA_D: usize = 90;
/// Samples along φ_d (half of MERL's 360: reciprocity makes φ_d and φ_d + π equal).
pub const RES_PHI_D: usize = 180;
/// Values per channel.
pub const CHANNEL_LEN: usize = RES_THETA_H * RES_THETA_D * RES_PHI_D;
/// Header bytes (three int32).
pub const HEADER_BYTES: usize = 12;
/// The exact size of a MERL `.binary` file: 34,992,012 bytes.
pub const FILE_BYTES: usize = HEADER_BYTES + 3 * CHANNEL_LEN * 8;
/// MERL's per-channel scale factors (R, G, B).
pub const SCALE: [f64; 3] = [1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0];

/// A measured isotropic BRDF table in MERL's layout, scaled to BRDF units. Missing entries keep
/// their (negative) sign so that averages can skip them; [`MerlBrdf::eval`] returns 0 for them.
#[derive(Clone, Debug)]
pub struct MerlBrdf {
    path: PathBuf,
    /// Scaled values, channel-major: `values[c * CHANNEL_LEN + index]`.
    values: Vec<f64>,
    missing: [usize; 3],
}

/// Bin indices of a lookup.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MerlIndex {
    /// θ_h bin (square-root mapping).
    pub theta_h: usize,
    /// θ_d bin.
    pub theta_d: usize,
    /// φ_d bin.
    pub phi_d: usize,
}

impl MerlIndex {
    /// Flat index within one channel block: i_φd + 180·i_θd + 180·90·i_θh.
    pub fn flat(&self) -> usize {
        self.phi_d + RES_PHI_D * self.theta_d + RES_PHI_D * RES_THETA_D * self.theta_h
    }
}

/// θ_h bin: 0 for θ_h ≤ 0, else ⌊√(θ_h/(π/2)·90·90)⌋ clamped to [0, 89] (the arithmetic order
/// follows MERL's reader so that bin edges round the same way).
pub fn theta_h_index(theta_h: f64) -> usize {
    if theta_h <= 0.0 {
        return 0;
    }
    let deg = theta_h / (PI / 2.0) * RES_THETA_H as f64;
    let t = (deg * RES_THETA_H as f64).sqrt();
    clamp_index(t, RES_THETA_H)
}

/// θ_d bin: ⌊θ_d/(π/2)·90⌋ clamped to [0, 89].
pub fn theta_d_index(theta_d: f64) -> usize {
    clamp_index(theta_d / (PI * 0.5) * RES_THETA_D as f64, RES_THETA_D)
}

/// φ_d bin: φ_d < 0 is folded by +π (reciprocity), then ⌊φ_d/π·360/2⌋ clamped to [0, 179].
pub fn phi_d_index(phi_d: f64) -> usize {
    let p = if phi_d < 0.0 { phi_d + PI } else { phi_d };
    clamp_index(p / PI * (2 * RES_PHI_D) as f64 / 2.0, RES_PHI_D)
}

fn clamp_index(x: f64, n: usize) -> usize {
    // `as` saturates (NaN → 0), then clamp to the last bin.
    (x.floor().max(0.0) as usize).min(n - 1)
}

/// The θ_h at the centre convention of entry `i` of the table: (i/90)²·π/2.
pub fn theta_h_of_index(i: usize) -> f64 {
    let t = i as f64 / RES_THETA_H as f64;
    t * t * PI / 2.0
}

/// Bin indices of a half/difference-angle configuration.
pub fn index_of(hd: &HalfDiff) -> MerlIndex {
    MerlIndex { theta_h: theta_h_index(hd.theta_h), theta_d: theta_d_index(hd.theta_d), phi_d: phi_d_index(hd.phi_d) }
}

/// Checks the 12-byte header: three little-endian int32 whose product is MERL's 90·90·180.
fn check_header(bytes: &[u8]) -> Result<(), String> {
    let dim = |i: usize| i32::from_le_bytes([bytes[4 * i], bytes[4 * i + 1], bytes[4 * i + 2], bytes[4 * i + 3]]);
    let dims = [dim(0), dim(1), dim(2)];
    let product = dims.iter().map(|&d| d as i64).product::<i64>();
    if product != CHANNEL_LEN as i64 {
        return Err(format!(
            "header dimensions {}x{}x{} (product {product}) are not MERL's 90x90x180 (product {CHANNEL_LEN}); \
             is this a MERL .binary file?",
            dims[0], dims[1], dims[2]
        ));
    }
    Ok(())
}

impl MerlBrdf {
    /// Reads and validates a MERL `.binary` file.
    pub fn read(path: &Path) -> Result<Self, BrdfError> {
        // The ceiling is the size of every MERL file: `/dev/zero` or a huge file is refused
        // after 35 MB, not after filling memory.
        let bytes = crate::io::read_bytes(path, "MERL", FILE_BYTES as u64, |_| Ok(())).map_err(|e| {
            let reason = match e {
                IoError::Os { error, .. } => format!("cannot read: {error}"),
                IoError::Invalid { reason, .. } => format!("{reason}, expected exactly {FILE_BYTES} bytes"),
                other => other.to_string(),
            };
            BrdfError::Merl { path: path.to_path_buf(), reason }
        })?;
        Self::from_bytes(path, &bytes)
    }

    /// Parses the bytes of a MERL `.binary` file (`path` is only used in messages).
    pub fn from_bytes(path: &Path, bytes: &[u8]) -> Result<Self, BrdfError> {
        let bad = |reason: String| BrdfError::Merl { path: path.to_path_buf(), reason };
        if bytes.len() < HEADER_BYTES {
            return Err(bad(format!(
                "truncated: {} bytes, too short for the 12-byte header (a MERL file has {FILE_BYTES} bytes)",
                bytes.len()
            )));
        }
        check_header(bytes).map_err(bad)?;
        if bytes.len() != FILE_BYTES {
            let size = match bytes.len() {
                n if n < FILE_BYTES => format!("truncated: {n} bytes"),
                _ => format!("too long: more than {FILE_BYTES} bytes"),
            };
            return Err(bad(format!(
                "{size}, expected exactly {FILE_BYTES} (12-byte header + 3 x {CHANNEL_LEN} float64)"
            )));
        }
        let mut values = Vec::with_capacity(3 * CHANNEL_LEN);
        let mut missing = [0usize; 3];
        for (n, chunk) in bytes[HEADER_BYTES..].chunks_exact(8).enumerate() {
            let raw =
                f64::from_le_bytes([chunk[0], chunk[1], chunk[2], chunk[3], chunk[4], chunk[5], chunk[6], chunk[7]]);
            let c = n / CHANNEL_LEN;
            if !raw.is_finite() {
                return Err(bad(format!(
                    "non-finite value {raw} in channel {} at index {}",
                    ["R", "G", "B"][c],
                    n % CHANNEL_LEN
                )));
            }
            if raw < 0.0 {
                missing[c] += 1;
            }
            values.push(raw * SCALE[c]);
        }
        Ok(MerlBrdf { path: path.to_path_buf(), values, missing })
    }

    /// The file this table came from.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Number of missing (negative) entries per channel.
    pub fn missing(&self) -> [usize; 3] {
        self.missing
    }

    /// The scaled table value of channel `c` at a bin; negative means missing.
    #[inline]
    pub fn value(&self, c: usize, index: MerlIndex) -> f64 {
        self.values[c * CHANNEL_LEN + index.flat()]
    }

    /// Table values (R, G, B) by MERL's lookup, with missing entries returned as negative.
    pub fn lookup_raw(&self, wi: DVec3, wo: DVec3) -> [f64; 3] {
        let idx = index_of(&halfdiff::from_directions(wi, wo));
        [self.value(0, idx), self.value(1, idx), self.value(2, idx)]
    }

    /// ρ(ω_i, ω_o) by MERL's lookup; missing entries are 0.
    pub fn eval(&self, wi: DVec3, wo: DVec3) -> [f64; 3] {
        self.lookup_raw(wi, wo).map(|v| v.max(0.0))
    }

    /// The half-angle curve ρ(θ_h) of each channel at the table's θ_h samples: the mean over
    /// θ_d below `max_theta_d` and all φ_d, skipping missing entries (Mahajan et al. 2008, §4:
    /// "averaging BRDF values across different θ_d, omitting grazing angles"). Returns
    /// (θ_h of each row, curve per channel); a row with no valid entry is 0.
    pub fn half_angle_curve(&self, max_theta_d: f64) -> (Vec<f64>, [Vec<f64>; 3]) {
        let theta_h: Vec<f64> = (0..RES_THETA_H).map(theta_h_of_index).collect();
        let td_rows: Vec<usize> =
            (0..RES_THETA_D).filter(|&j| (j as f64) * (PI / 2.0) / (RES_THETA_D as f64) < max_theta_d).collect();
        let curves = [0, 1, 2].map(|c| {
            (0..RES_THETA_H)
                .map(|i| {
                    let (mut sum, mut count) = (0.0, 0usize);
                    for &j in &td_rows {
                        for k in 0..RES_PHI_D {
                            let v = self.value(c, MerlIndex { theta_h: i, theta_d: j, phi_d: k });
                            if v >= 0.0 {
                                sum += v;
                                count += 1;
                            }
                        }
                    }
                    if count == 0 {
                        0.0
                    } else {
                        sum / count as f64
                    }
                })
                .collect()
        });
        (theta_h, curves)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn synthetic_bytes(fill: impl Fn(usize, usize) -> f64) -> Vec<u8> {
        let mut bytes = Vec::with_capacity(FILE_BYTES);
        for d in [90i32, 90, 180] {
            bytes.extend_from_slice(&d.to_le_bytes());
        }
        for c in 0..3 {
            for i in 0..CHANNEL_LEN {
                bytes.extend_from_slice(&fill(c, i).to_le_bytes());
            }
        }
        bytes
    }

    #[test]
    fn scales_channels_and_counts_missing() {
        let bytes = synthetic_bytes(|c, i| if i == 7 && c == 1 { -1.0 } else { 1500.0 });
        let m = MerlBrdf::from_bytes(Path::new("t.binary"), &bytes).unwrap();
        assert_eq!(m.missing(), [0, 1, 0]);
        let idx = MerlIndex { theta_h: 0, theta_d: 0, phi_d: 7 };
        assert_eq!(idx.flat(), 7);
        assert!((m.value(0, idx) - 1.0).abs() < 1e-15);
        assert!(m.value(1, idx) < 0.0);
        assert!((m.value(2, MerlIndex { theta_h: 3, theta_d: 0, phi_d: 0 }) - 1.66).abs() < 1e-15);
    }

    #[test]
    fn rejects_bad_headers_and_sizes() {
        let good = synthetic_bytes(|_, _| 0.0);
        let err = |b: &[u8]| MerlBrdf::from_bytes(Path::new("x.binary"), b).unwrap_err().to_string();
        assert!(err(&good[..5]).contains("truncated"));
        assert!(err(&good[..good.len() - 8]).contains("truncated"));
        let mut long = good.clone();
        long.push(0);
        assert!(err(&long).contains("too long"));
        let mut wrong = good.clone();
        wrong[0..4].copy_from_slice(&91i32.to_le_bytes());
        let e = err(&wrong);
        assert!(e.contains("91x90x180") && e.contains("x.binary"), "{e}");
        let mut nan = good;
        nan[12..20].copy_from_slice(&f64::NAN.to_le_bytes());
        assert!(err(&nan).contains("non-finite"));
    }

    #[test]
    fn theta_h_mapping_is_the_square_root_one() {
        // Entry i sits at θ_h = (i/90)²·π/2; slightly above it must fall in bin i.
        for i in [1usize, 2, 10, 45, 89] {
            let t = theta_h_of_index(i) * (1.0 + 1e-9);
            assert_eq!(theta_h_index(t), i);
        }
        assert_eq!(theta_h_index(0.0), 0);
        assert_eq!(theta_h_index(-0.1), 0);
        assert_eq!(theta_h_index(3.0), 89);
        assert_eq!(phi_d_index(-0.5 * PI / 180.0), 179);
        assert_eq!(phi_d_index(f64::NAN), 0);
    }
}
