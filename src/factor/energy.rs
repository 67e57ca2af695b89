//! Energy curves of a factorization: the energy of K terms is Σ_{k≤K} σ_k², a fraction of the
//! total Σ σ_k² = ‖M‖_F² (the paper's "99 % of the energy", §3.3).

/// The energy fractions reported by default: 90, 95, 99 and 99.9 %.
pub const STANDARD_FRACTIONS: [f64; 4] = [0.90, 0.95, 0.99, 0.999];

/// Cumulative energy fractions: entry k is Σ_{j≤k} σ_j² / Σ σ² (so entry K−1 is the energy of
/// K terms). All zeros for a zero matrix.
pub fn cumulative_energy(singular_values: &[f64]) -> Vec<f64> {
    cumulative_energy_of(singular_values, singular_values.iter().map(|s| s * s).sum())
}

/// [`cumulative_energy`] against a known total (‖M‖_F², when only leading σ are known).
pub fn cumulative_energy_of(singular_values: &[f64], total: f64) -> Vec<f64> {
    let mut acc = 0.0;
    singular_values
        .iter()
        .map(|s| {
            acc += s * s;
            if total > 0.0 {
                acc / total
            } else {
                0.0
            }
        })
        .collect()
}

/// The smallest K whose terms hold at least `fraction` of the energy (0 for a zero matrix).
/// A relative slack of 1e-12 absorbs rounding when the fraction is reached exactly.
pub fn terms_for_fraction(singular_values: &[f64], fraction: f64) -> usize {
    terms_for_fraction_of(singular_values, singular_values.iter().map(|s| s * s).sum(), fraction)
}

/// [`terms_for_fraction`] against a known total; `len + 1` if the known terms fall short.
pub fn terms_for_fraction_of(singular_values: &[f64], total: f64, fraction: f64) -> usize {
    if total == 0.0 {
        return 0;
    }
    let cumulative = cumulative_energy_of(singular_values, total);
    cumulative.iter().position(|&c| c >= fraction - 1e-12).map_or(cumulative.len() + 1, |k| k + 1)
}

/// Relative Frobenius error of the best K-term reconstruction: √(Σ_{k>K} σ_k² / Σ σ_k²)
/// (Eckart–Young: truncating the SVD is the optimal rank-K approximation).
pub fn reconstruction_error(singular_values: &[f64], terms: usize) -> f64 {
    reconstruction_error_of(singular_values, singular_values.iter().map(|s| s * s).sum(), terms)
}

/// [`reconstruction_error`] against a known total: √((total − Σ_{k≤K} σ_k²)/total).
pub fn reconstruction_error_of(singular_values: &[f64], total: f64, terms: usize) -> f64 {
    if total == 0.0 {
        return 0.0;
    }
    let head: f64 = singular_values.iter().take(terms).map(|s| s * s).sum();
    ((total - head).max(0.0) / total).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_terms_at_energy_fractions() {
        // Energies 16, 9, 4, 1 of total 30.
        let s = [4.0, 3.0, 2.0, 1.0];
        assert_eq!(terms_for_fraction(&s, 0.5), 1);
        assert_eq!(terms_for_fraction(&s, 25.0 / 30.0), 2);
        assert_eq!(terms_for_fraction(&s, 0.9), 3);
        assert_eq!(terms_for_fraction(&s, 0.99), 4);
        assert_eq!(terms_for_fraction(&[0.0, 0.0], 0.99), 0);
        assert!((reconstruction_error(&s, 2) - (5.0f64 / 30.0).sqrt()).abs() < 1e-15);
        assert_eq!(reconstruction_error(&s, 4), 0.0);
    }
}
