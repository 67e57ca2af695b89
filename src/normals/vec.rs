//! The little vector arithmetic the parameterizations share, in f64 (the error of a 64-bit code
//! is ~5e-10 rad, far above f64's 1.1e-16 but far below f32's 6e-8).

/// A direction in the prtkit frame (right-handed, +Z up).
pub type Dir = [f64; 3];

/// Dot product.
#[inline]
pub fn dot(a: Dir, b: Dir) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Cross product.
#[inline]
pub fn cross(a: Dir, b: Dir) -> Dir {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// Euclidean length.
#[inline]
pub fn length(a: Dir) -> f64 {
    dot(a, a).sqrt()
}

/// `a / |a|` (the caller guarantees `a != 0`).
#[inline]
pub fn normalize(a: Dir) -> Dir {
    let inv = 1.0 / length(a);
    [a[0] * inv, a[1] * inv, a[2] * inv]
}

/// Squared distance `|a - b|^2`: the chord length, monotone in the angle between unit vectors
/// and, unlike `1 - a·b`, free of cancellation when the angle is tiny (Meyer et al.'s range
/// rounding at 48 bits compares angles of ~1e-7 rad, whose cosines all round to 1 in f32).
#[inline]
pub fn distance_squared(a: Dir, b: Dir) -> f64 {
    let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    dot(d, d)
}

/// `σ(t)` of Meyer et al. eq. 9: `+1` for `t >= 0` (including `-0.0`), `-1` otherwise.
#[inline]
pub fn sign_not_zero(t: f64) -> f64 {
    if t >= 0.0 {
        1.0
    } else {
        -1.0
    }
}

/// The angle between two directions of any length, `atan2(|a×b|, a·b)`: accurate for tiny
/// angles where `acos(a·b)` loses everything (at 1e-7 rad, `acos` of a rounded cosine is off by
/// 100 % in f32 and ~1e-9 rad in f64).
#[inline]
pub fn angle_between(a: Dir, b: Dir) -> f64 {
    length(cross(a, b)).atan2(dot(a, b))
}

/// `(sin(t·π/2), cos(t·π/2))` for `t` in `[-1, 1]`, exact at `t ∈ {-1, 0, 1}`: the argument is
/// reduced by the complement identity so the results hit `0` and `±1` exactly (`cos(π/2)` in
/// floating point is 6e-17, which would tilt the poles of spherical coordinates).
#[inline]
pub fn sincos_half_pi(t: f64) -> (f64, f64) {
    let half_pi = std::f64::consts::FRAC_PI_2;
    if t.abs() <= 0.5 {
        let (s, c) = (t * half_pi).sin_cos();
        (s, c)
    } else {
        // sin(tπ/2) = σ(t)·cos((1-|t|)π/2), cos(tπ/2) = sin((1-|t|)π/2); 1-|t| is exact here.
        let (s, c) = ((1.0 - t.abs()) * half_pi).sin_cos();
        (sign_not_zero(t) * c, s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atan2_angle_is_accurate_where_acos_fails() {
        let a = [1.0, 0.0, 0.0];
        for k in [1e-3f64, 1e-7, 1e-9, 1e-12] {
            let b = [k.cos(), k.sin(), 0.0];
            assert!((angle_between(a, b) - k).abs() <= 1e-15 * k + 1e-30, "{k}");
        }
        // acos of the f64 dot product at 1e-9 rad is visibly wrong: the reason for atan2.
        let b = [1e-9f64.cos(), 1e-9f64.sin(), 0.0];
        assert!((dot(a, b).acos() - 1e-9).abs() > 1e-10);
    }

    #[test]
    fn sincos_exact_at_quarter_turns() {
        assert_eq!(sincos_half_pi(0.0), (0.0, 1.0));
        assert_eq!(sincos_half_pi(1.0), (1.0, 0.0));
        assert_eq!(sincos_half_pi(-1.0), (-1.0, 0.0));
        for i in 0..=200 {
            let t = -1.0 + i as f64 / 100.0;
            let (s, c) = sincos_half_pi(t);
            let (s0, c0) = (t * std::f64::consts::FRAC_PI_2).sin_cos();
            assert!((s - s0).abs() < 1e-15 && (c - c0).abs() < 1e-15, "{t}");
        }
    }
}
