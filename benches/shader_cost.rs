//! Cost of one area sample relative to one point sample (Heidrich, Slusallek & Seidel 1998,
//! Table 1: 1:5.4 to 1:10.4), per shader of `testdata/shaders`, single-threaded.
//!
//! Every node of one quadtree level (`SHADER_COST_DEPTH`, default 7: 128×128 nodes) is evaluated
//! once per arithmetic through the same interpreter and the same `evaluate_node` the sampler
//! uses; point mode takes 8 random points per node. The arithmetics alternate for
//! `SHADER_COST_ROUNDS` rounds (default 5) and the fastest round of each counts, so that load
//! from other processes on a shared machine distorts the ratio less than one sequential run.
//!
//! Run: `cargo bench --bench shader_cost`.

use prtkit::shader::sampler::{evaluate_node, Arith, Domain, SampleConfig};
use prtkit::shader::Shader;
use std::time::Instant;

const SHADERS: [&str; 5] = ["screen", "wood", "marble", "bumpmap", "eroded"];
const POINTS_PER_NODE: usize = 8;

fn env_or(name: &str, default: u32) -> u32 {
    std::env::var(name).ok().and_then(|s| s.parse().ok()).unwrap_or(default)
}

/// Seconds to evaluate every node of `depth` once in `arith`.
fn time_level(shader: &Shader, arith: Arith, depth: u32) -> f64 {
    let cfg = SampleConfig {
        tolerance: 0.0,
        max_depth: depth,
        arith,
        domain: Domain::Texture,
        points_per_node: POINTS_PER_NODE,
        seed: 1,
    };
    let n = 1u32 << depth;
    let start = Instant::now();
    for iy in 0..n {
        for ix in 0..n {
            match evaluate_node(shader, &cfg, depth, ix, iy) {
                Ok(node) => {
                    std::hint::black_box(node);
                }
                Err(e) => panic!("{e}"),
            }
        }
    }
    start.elapsed().as_secs_f64()
}

fn main() {
    let depth = env_or("SHADER_COST_DEPTH", 7);
    let rounds = env_or("SHADER_COST_ROUNDS", 5).max(1);
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/testdata/shaders");
    let nodes = (1u64 << depth) * (1u64 << depth);
    println!("shader_cost: depth {depth} ({nodes} nodes), {rounds} rounds, fastest round of each arithmetic");
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
                best[k] = best[k].min(time_level(&shader, arith, depth));
            }
        }
        let per = |k: usize| {
            let samples = if k == 2 { nodes * POINTS_PER_NODE as u64 } else { nodes };
            best[k] / samples as f64 * 1e6
        };
        let (a, i, p) = (per(0), per(1), per(2));
        println!("| {name} | {a:.2} | {i:.2} | {p:.3} | 1:{:.2} | 1:{:.2} |", a / p, i / p);
    }
}
