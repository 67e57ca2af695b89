//! Encode/decode throughput of octahedron normal vectors (Meyer et al. 2010) at 32 bits on 10^7
//! normals, all cores, plus a cross-check against meshoptimizer's octahedral filter (the
//! `meshopt` crate, its C++ compiled by `cc` with default flags) on the same normals and the same
//! threads in the same run: error and speed. prtkit's kernels dispatch to AVX2 where the CPU has
//! it (`normals::onv::kernel_isa`, printed).
//!
//! Run: `cargo bench --bench normals` (env `NORMALS_BENCH_COUNT` changes the count).

use glam::DVec3;
use prtkit::normals::metrics::angle_between;
use prtkit::normals::{Codec, Scheme};
use prtkit::rng::SplitMix64;
use rayon::prelude::*;
use std::time::Instant;

/// CPU seconds used by this process so far (user + system, /proc/self/stat, 100 ticks/s).
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let after = stat.rsplit_once(')').map_or("", |(_, rest)| rest);
    let f: Vec<f64> = after.split_whitespace().map(|x| x.parse().unwrap_or(0.0)).collect();
    (f.get(11).copied().unwrap_or(0.0) + f.get(12).copied().unwrap_or(0.0)) / 100.0
}

/// Timing of a phase: best wall time of `reps` runs, and CPU seconds per run (all threads).
struct Timing {
    wall: f64,
    cpu: f64,
}

impl Timing {
    /// "wall M/s (M/s per CPU-second × threads)": the second number is what the machine would
    /// do with its cores to itself, independent of other processes' load.
    fn show(&self, n: usize, threads: usize) -> String {
        format!("{:.1} ({:.1})", n as f64 / self.wall / 1e6, n as f64 / self.cpu * threads as f64 / 1e6)
    }
}

fn best_of(reps: usize, mut f: impl FnMut()) -> Timing {
    let mut best = f64::INFINITY;
    let cpu0 = cpu_seconds();
    for _ in 0..reps {
        let t = Instant::now();
        f();
        best = best.min(t.elapsed().as_secs_f64());
    }
    Timing { wall: best, cpu: (cpu_seconds() - cpu0) / reps as f64 }
}

fn vec(v: &[f32; 3]) -> DVec3 {
    DVec3::from(v.map(f64::from))
}

fn max_error_f32(a: &[[f32; 3]], b: &[[f32; 3]]) -> (f64, f64) {
    let errs: Vec<f64> = a.par_iter().zip(b.par_iter()).map(|(x, y)| angle_between(vec(x), vec(y))).collect();
    let max = errs.iter().copied().fold(0.0, f64::max);
    (max, errs.iter().sum::<f64>() / errs.len() as f64)
}

fn main() {
    let n: usize = std::env::var("NORMALS_BENCH_COUNT").ok().and_then(|s| s.parse().ok()).unwrap_or(10_000_000);
    let threads = rayon::current_num_threads();
    let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    println!(
        "normals bench: {n} random unit normals, {threads} threads, best of 5, prtkit kernels: {}; load average at start: {}",
        prtkit::normals::onv::kernel_isa(),
        load.trim()
    );
    let normals: Vec<[f32; 3]> = (0..n.div_ceil(1 << 16))
        .into_par_iter()
        .flat_map_iter(|c| {
            let mut s = SplitMix64::for_chunk(2024, c as u64);
            (0..1 << 16).map(move |_| s.direction().as_vec3().to_array())
        })
        .take_any(n)
        .collect();
    let mut codes = vec![0u64; n];
    let mut decoded = vec![[0f32; 3]; n];
    println!("Throughput in M normals/s: best wall-clock run, and in parentheses the CPU-time rate");
    println!("(normals per CPU-second × {threads} threads), which discounts other processes' load.");
    println!();
    println!("| codec | encode M/s | decode M/s | max error (rad) | mean error (rad) |");
    println!("| --- | --- | --- | --- | --- |");
    for scheme in [Scheme::OnvDomain, Scheme::OnvRange] {
        let codec = Codec::new(scheme, 32).expect("32 bits is a valid budget");
        let te = best_of(5, || codec.encode_all_f32(&normals, &mut codes));
        let td = best_of(5, || codec.decode_all_f32(&codes, &mut decoded));
        let (max, mean) = max_error_f32(&normals, &decoded);
        println!("| prtkit {scheme} 32 | {} | {} | {max:.3e} | {mean:.3e} |", te.show(n, threads), td.show(n, threads));
    }
    meshopt_cross_check(&normals);
}

/// meshoptimizer's `meshopt_encodeFilterOct` with 16-bit components (stride 8: x, y as the
/// octahedral pair, plus the scale and w slots), i.e. 32 bits of direction like ONV at 32 bits.
/// Its decoder writes SNORM16 xyz, so the decoded direction also carries that re-quantization.
/// The filters are single-threaded C++; we run them over per-thread chunks for both cores.
fn meshopt_cross_check(normals: &[[f32; 3]]) {
    let n = normals.len();
    let input: Vec<f32> = normals.iter().flat_map(|v| [v[0], v[1], v[2], 0.0]).collect();
    let chunk = 1 << 16;
    let mut encoded = vec![0u8; n * 8];
    let te = best_of(5, || {
        encoded.par_chunks_mut(chunk * 8).zip(input.par_chunks(chunk * 4)).for_each(|(dst, src)| {
            let count = src.len() / 4;
            // SAFETY: dst holds count*8 bytes, src count*4 floats; stride 8 with 16-bit output.
            unsafe { meshopt::ffi::meshopt_encodeFilterOct(dst.as_mut_ptr().cast(), count, 8, 16, src.as_ptr()) };
        })
    });
    let mut buffer = encoded.clone();
    let td = best_of(5, || {
        buffer.copy_from_slice(&encoded);
        buffer.par_chunks_mut(chunk * 8).for_each(|b| {
            // SAFETY: in-place decode of b.len()/8 vectors of stride 8.
            unsafe { meshopt::ffi::meshopt_decodeFilterOct(b.as_mut_ptr().cast(), b.len() / 8, 8) };
        })
    });
    let decoded: Vec<[f32; 3]> = buffer
        .chunks_exact(8)
        .map(|c| {
            let s = |i: usize| i16::from_le_bytes([c[2 * i], c[2 * i + 1]]) as f32 / 32767.0;
            [s(0), s(1), s(2)]
        })
        .collect();
    let (max, mean) = max_error_f32(normals, &decoded);
    // The decode timing includes the copy that restores the encoded buffer (in-place API).
    let threads = rayon::current_num_threads();
    println!(
        "| meshopt filter oct 16+16 | {} | {} | {max:.3e} | {mean:.3e} |",
        te.show(n, threads),
        td.show(n, threads)
    );
    println!("(meshopt decode time includes re-copying the encoded buffer, since its decoder works in place)");
}
