//! `factor-brdf`: the in-out SVD of one BRDF (Mahajan, Tseng & Ramamoorthi 2008): singular
//! values, energy curve, K at 90/95/99/99.9 %, reconstruction error, factor maps.

use super::common::{Execution, Outcome};
use crate::brdf::BrdfSpec;
use crate::factor::document::{self, FactorBody, Reconstruction};
use crate::factor::{energy, maps, svd, Channel, Domain, Method, Sampling};
use crate::io::{self, Document, Output, Provenance};
use anyhow::{Context, Result};
use clap::Parser;
use std::collections::BTreeMap;
use std::path::PathBuf;

/// Factor a BRDF into in-out terms by SVD and report how many terms each energy fraction needs.
#[derive(Debug, Parser)]
#[command(name = "factor-brdf", version, about, long_about = None)]
pub struct Args {
    /// BRDF spec, e.g. `phong:s=30`, `torrance-sparrow:sigma=0.2`, `merl:gold.binary`
    /// (docs/brdf-specs.md).
    pub brdf: String,

    #[command(flatten)]
    pub matrix: MatrixArgs,

    /// Write the factor maps g_k, h_k (factors.exr with layers g_000, h_000, …, and a
    /// factors.png contact sheet) into this directory.
    #[arg(long, value_name = "DIR")]
    pub maps: Option<PathBuf>,

    /// Write the leading factors g_k, h_k sampled on the grid to this EXR (the document names
    /// it), for `render --shading factored --factors DOC.json` (docs/formats/factor.md).
    #[arg(long, value_name = "FILE.exr")]
    pub factors: Option<PathBuf>,

    /// Number of leading terms drawn by --maps and stored by --factors.
    #[arg(long, default_value_t = 16, value_name = "N")]
    pub terms: usize,

    /// Memory budget, e.g. 512M, 4G (binary units).
    #[arg(long, default_value = "4G", value_parser = parse_memory)]
    pub max_memory: u128,

    /// The JSON document (`prtkit.factor`, docs/formats/factor.md); `-` is stdout.
    #[arg(short, long, default_value = "-")]
    pub output: String,

    /// Also print a one-line JSON summary on stdout (when --output is a file).
    #[arg(long)]
    pub json: bool,

    #[command(flatten)]
    pub run: Execution,
}

/// Parses a memory size with an optional K/M/G/T suffix (powers of 1024).
pub fn parse_memory(s: &str) -> Result<u128, String> {
    let t = s.trim().trim_end_matches(['B', 'b']).trim_end_matches('i');
    let (num, mult) = match t.chars().last() {
        Some('K' | 'k') => (&t[..t.len() - 1], 1u128 << 10),
        Some('M' | 'm') => (&t[..t.len() - 1], 1 << 20),
        Some('G' | 'g') => (&t[..t.len() - 1], 1 << 30),
        Some('T' | 't') => (&t[..t.len() - 1], 1 << 40),
        _ => (t, 1),
    };
    let v: f64 = num.trim().parse().map_err(|_| format!("expected a size like 512M or 4G, got {s:?}"))?;
    if !(v.is_finite() && v > 0.0) {
        return Err(format!("memory size must be positive, got {s:?}"));
    }
    Ok((v * mult as f64) as u128)
}

/// Percent label of an energy fraction: 0.999 → "99.9%".
pub fn percent_label(f: f64) -> String {
    let p = (f * 1000.0).round() / 10.0;
    if p.fract() == 0.0 {
        format!("{}%", p as i64)
    } else {
        format!("{p}%")
    }
}

/// How the BRDF matrix is sampled and factored: shared by `factor-brdf` and `count-terms`.
#[derive(Debug, clap::Args)]
pub struct MatrixArgs {
    /// Directions sampled for ω_i and ω_o: the full sphere or the visible hemispheres.
    #[arg(long, value_enum, default_value_t = Domain::Hemisphere)]
    pub domain: Domain,

    /// Grid bins along cos θ and along φ (n² directions per side; the paper uses 40).
    #[arg(long, default_value_t = 40)]
    pub resolution: usize,

    /// Fold max(cos θ_i, 0) into the matrix (off by default, as in the paper; count-terms
    /// makes no closed-form prediction then).
    #[arg(long)]
    pub cosine: bool,

    /// Scalar factored for RGB (measured) data; analytic models are grey.
    #[arg(long, value_enum, default_value_t = Channel::Luminance)]
    pub channel: Channel,

    /// SVD method: fft (isotropic BRDFs, block-circulant in φ), dense, randomized (leading
    /// terms of the dense matrix, for large n), or auto (fft when isotropic, else dense).
    #[arg(long, value_enum, default_value_t = Method::Auto)]
    pub method: Method,
}

impl MatrixArgs {
    /// The sampling these options describe.
    pub fn sampling(&self) -> Sampling {
        Sampling { resolution: self.resolution, domain: self.domain, cosine: self.cosine, channel: self.channel }
    }
}

/// Runs `factor-brdf`.
pub fn run(args: Args) -> Result<Outcome> {
    let spec = BrdfSpec::parse(&args.brdf)?;
    let output = Output::parse(&args.output);
    output.check_writable()?;
    let sampling = args.matrix.sampling();
    let wants_factors = args.maps.is_some() || args.factors.is_some();
    let terms = if wants_factors { args.terms.min(sampling.grid().len()) } else { 0 };
    if wants_factors && terms == 0 {
        anyhow::bail!("--terms must be at least 1 with --maps or --factors");
    }
    if let Some(p) = &args.factors {
        Output::File(p.clone()).check_writable()?;
    }
    let brdf = spec.load()?;
    let method = svd::resolve_method(&brdf, args.matrix.method)?;
    svd::check_budget(&sampling, method, terms, args.max_memory)?;
    let bar = args.run.start()?;
    let f = svd::factor(&brdf, &sampling, method, terms, &bar)?;
    let s = &f.singular_values;
    let cumulative = f.cumulative_energy();
    let mut term_counts = BTreeMap::new();
    let mut reconstruction = Vec::new();
    let mut ks: Vec<usize> = Vec::new();
    for fraction in energy::STANDARD_FRACTIONS {
        let k = f.terms_for(fraction);
        term_counts.insert(percent_label(fraction), k);
        ks.push(k);
    }
    if terms > 0 {
        ks.push(terms);
    }
    ks.sort_unstable();
    ks.dedup();
    for k in ks {
        reconstruction.push(Reconstruction {
            terms: k,
            energy: if k == 0 { 0.0 } else { cumulative.get(k - 1).copied().unwrap_or(1.0) },
            relative_frobenius_error: f.reconstruction_error(k),
        });
    }
    let maps_dir = if let Some(dir) = &args.maps {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create directory {}", dir.display()))?;
        let layers = maps::layers(&f);
        let refs: Vec<(&str, &io::RgbImage)> = layers.iter().map(|(n, i)| (n.as_str(), i)).collect();
        io::exr::write_layers(&dir.join("factors.exr"), &refs)?;
        io::image::write_image(&dir.join("factors.png"), &maps::contact_sheet(&f), 0.0)?;
        Some(dir.display().to_string())
    } else {
        None
    };
    let factors = match &args.factors {
        Some(p) => Some(document::write_factors(p, &f, terms)?),
        None => None,
    };
    let body = FactorBody {
        brdf: brdf.spec(),
        domain: args.matrix.domain,
        resolution: args.matrix.resolution,
        directions_per_side: sampling.grid().len(),
        cosine: args.matrix.cosine,
        channel: args.matrix.channel,
        method: f.method,
        matrix: format!(
            "M[o,i] = rho(w_i, w_o){} * dOmega, dOmega = {}/n^2; n x n cells uniform in cos(theta) and phi, samples at bin midpoints; direction index = j*n + k (j: cos(theta) bin from the pole, k: phi bin)",
            if args.matrix.cosine { " * max(cos(theta_i), 0)" } else { "" },
            if args.matrix.domain == Domain::Sphere { "4 pi" } else { "2 pi" }
        ),
        total_energy: f.total_energy,
        singular_values: s.clone(),
        cumulative_energy: cumulative,
        terms: term_counts.clone(),
        reconstruction,
        azimuthal_frequency: f.azimuthal_frequency.clone(),
        maps: maps_dir,
        factors,
    };
    let inputs = match &spec {
        BrdfSpec::Merl(p) => vec![p.display().to_string()],
        _ => vec![],
    };
    let doc = Document::new(document::FORMAT, document::VERSION, Provenance::current("factor-brdf", inputs), body);
    output.write(doc.to_json().as_bytes())?;
    let summary: Vec<String> = term_counts.iter().map(|(k, v)| format!("{k}: {v}")).collect();
    eprintln!(
        "factor-brdf: {} on the {} at n = {} ({} method): K {}",
        brdf.spec(),
        args.matrix.domain,
        args.matrix.resolution,
        f.method,
        summary.join(", ")
    );
    if args.json && output != Output::Stdout {
        let line = serde_json::json!({
            "brdf": brdf.spec(), "domain": args.matrix.domain, "resolution": args.matrix.resolution,
            "method": f.method, "terms": term_counts, "output": output.display(),
        });
        println!("{line}");
    }
    Ok(Outcome::Success)
}
