//! Cost of one area sample relative to one point sample (Heidrich, Slusallek & Seidel 1998,
//! Table 1: 1:5.4 to 1:10.4), per shader of `testdata/shaders`, single-threaded.
//!
//! The full quadtree down to `SHADER_COST_DEPTH` (default 8: 87381 nodes, as in the equal-depth
//! table of `scripts/reproduce-shader-table.sh`) is sampled once per arithmetic by the sampler
//! itself on one thread; point mode takes 8 random points per node. The arithmetics alternate
//! for `SHADER_COST_ROUNDS` rounds (default 3) and the fastest round of each counts, so that
//! load from other processes on a shared machine distorts the ratio less than one sequential
//! run.
//!
//! Run: `cargo bench --bench shader_cost`.

use prtkit::progress::NoProgress;
use prtkit::shader::sampler::{sample, Arith, Domain, SampleConfig};
use prtkit::shader::Shader;
use std::time::Instant;

const SHADERS: [&str; 5] = ["screen", "wood", "marble", "bumpmap", "eroded"];
const POINTS_PER_NODE: usize = 8;

fn env_or(name: &str, default: u32) -> u32 {
    std::env::var(name).ok().and_then(|s| s.parse().ok()).unwrap_or(default)
}

/// Seconds to sample the full tree down to `depth` in `arith`, and the evaluations made.
fn time_tree(shader: &Shader, arith: Arith, depth: u32) -> (f64, u64) {
    let cfg = SampleConfig {
        tolerance: 0.0,
        max_depth: depth,
        arith,
        domain: Domain::Texture,
        points_per_node: POINTS_PER_NODE,
        seed: 1,
    };
    let start = Instant::now();
    let sampled = sample(shader, &cfg, &NoProgress).unwrap_or_else(|e| panic!("{e}"));
    (start.elapsed().as_secs_f64(), sampled.evaluations)
}

fn main() {
    let depth = env_or("SHADER_COST_DEPTH", 8);
    let rounds = env_or("SHADER_COST_ROUNDS", 3).max(1);
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/testdata/shaders");
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap_or_else(|e| panic!("{e}"));
    println!("shader_cost: full tree to depth {depth}, one thread, {rounds} rounds, fastest round of each arithmetic");
    println!(
        "| shader | affine µs/sample | interval µs/sample | point µs/sample | affine : point | interval : point |"
    );
    println!("|---|---:|---:|---:|---:|---:|");
    for name in SHADERS {
        let path = format!("{dir}/{name}.sl");
        let source = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
        let shader = Shader::compile(&source, &path).unwrap_or_else(|e| panic!("{e}"));
        let mut best = [f64::INFINITY; 3];
        for _ in 0..rounds {
            for (k, arith) in [Arith::Affine, Arith::Interval, Arith::Point].into_iter().enumerate() {
                let (seconds, evaluations) = pool.install(|| time_tree(&shader, arith, depth));
                best[k] = best[k].min(seconds / evaluations as f64 * 1e6);
            }
        }
        let (a, i, p) = (best[0], best[1], best[2]);
        println!("| {name} | {a:.2} | {i:.2} | {p:.3} | 1:{:.2} | 1:{:.2} |", a / p, i / p);
    }
}
