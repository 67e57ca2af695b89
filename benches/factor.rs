//! Benchmark of the in-out SVD (Mahajan et al. 2008): K(99 %) for Phong s = 30 on the 40⁴
//! hemisphere (the paper's resolution; target < 2 s) and on the n = 64 sphere (a 4096 × 4096
//! matrix; target < 20 s), by the block-circulant FFT method, the randomized SVD of the dense
//! matrix and faer's full dense SVD.
//!
//! Run: `cargo bench --bench factor` (prints a Markdown table; `scripts/reproduce-terms.sh`
//! copies it into docs/results/terms.md). Set `PRTKIT_BENCH_SKIP_DENSE_64=1` to skip the slow
//! dense 4096² case.

use prtkit::brdf::Brdf;
use prtkit::factor::{factor, Channel, Domain, Method, Sampling};
use prtkit::progress::NoProgress;
use std::time::Instant;

fn time_k99(brdf: &Brdf, n: usize, domain: Domain, method: Method, runs: usize) -> (f64, usize) {
    let sampling = Sampling { resolution: n, domain, cosine: false, channel: Channel::Luminance };
    let mut times = Vec::new();
    let mut k = 0;
    for _ in 0..runs {
        let start = Instant::now();
        let f = factor(brdf, &sampling, method, 0, &NoProgress).expect("factorization");
        k = f.terms_for(0.99);
        times.push(start.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    (times[times.len() / 2], k)
}

fn main() {
    let brdf = Brdf::parse("phong:s=30").expect("spec");
    let skip_dense_64 = std::env::var_os("PRTKIT_BENCH_SKIP_DENSE_64").is_some();
    println!("| case | matrix | method | K(99 %) | time (median) | target |");
    println!("| --- | --- | --- | ---: | ---: | --- |");
    let cases = [
        ("phong:s=30, hemisphere, n = 40", 40, Domain::Hemisphere, "1600 x 1600", "< 2 s"),
        ("phong:s=30, sphere, n = 64", 64, Domain::Sphere, "4096 x 4096", "< 20 s"),
    ];
    for (label, n, domain, size, target) in cases {
        for (method, runs) in [
            (Method::Fft, 5),
            (Method::Randomized, if n == 64 { 1 } else { 3 }),
            (Method::Dense, if n == 64 { 1 } else { 3 }),
        ] {
            if method == Method::Dense && n == 64 && skip_dense_64 {
                println!("| {label} | {size} | dense | - | skipped | {target} |");
                continue;
            }
            let (t, k) = time_k99(&brdf, n, domain, method, runs);
            println!(
                "| {label} | {size} | {method} ({runs} run{}) | {k} | {t:.3} s | {target} |",
                if runs > 1 { "s" } else { "" }
            );
        }
    }
    println!();
    println!("threads available to rayon: {}", rayon::current_num_threads());
}
