//! Writes the split-sum DFG terms that `ibl` ships (`prtkit::ibl::dfg`): A and B of every texel
//! of the 128² table by the default quadrature, f64 little-endian pairs, row-major.
//!
//!     cargo run --release --example dfg_table -- data/dfg-128.bin

use anyhow::{Context, Result};
use prtkit::ibl::dfg::{integrate_table, DEFAULT_ORDER, SHIPPED_SIZE};

fn main() -> Result<()> {
    let path = std::env::args().nth(1).context("usage: dfg_table OUTPUT")?;
    let terms = integrate_table(SHIPPED_SIZE, DEFAULT_ORDER)?;
    let bytes: Vec<u8> = terms.iter().flat_map(|t| [t.scale, t.bias]).flat_map(f64::to_le_bytes).collect();
    std::fs::write(&path, bytes).with_context(|| format!("cannot write {path}"))?;
    Ok(())
}
