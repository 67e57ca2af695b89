//! The layers of `docs/architecture.md`, checked: every `crate::MODULE` a source file of `src/`
//! names outside comments is a module below its own in [`LAYERS`], so a new back-edge (a cycle
//! such as `render` ↔ `transfer`, or a vocabulary module reaching up into a domain one) fails here
//! with the file and the line that adds it.

use std::path::Path;

/// The top-level modules, bottom up: each may use only those before it. `cli` sits on top.
const LAYERS: &[&str] = &[
    // Vocabulary and util.
    "sphere",
    "quadrature",
    "rng",
    "progress",
    "limits",
    "io",
    "metrics",
    // Domain modules.
    "affine",
    "shader",
    "normals",
    "envmap",
    "sh",
    "brdf",
    "ibl",
    "factor",
    "prefilter",
    "mesh",
    "transfer",
    "render",
    // The command line.
    "cli",
];

/// The top-level module a source file belongs to (`src/ibl/stage.rs` → `ibl`, `src/limits.rs` →
/// `limits`); `None` for `lib.rs` and the binaries.
fn module_of(src: &Path, file: &Path) -> Option<String> {
    let relative = file.strip_prefix(src).ok()?;
    let first = relative.components().next()?.as_os_str().to_str()?.to_string();
    match first.strip_suffix(".rs") {
        Some("lib") => None,
        Some(name) => Some(name.to_string()),
        None if first == "bin" => None,
        None => Some(first),
    }
}

fn rust_files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The modules `crate::NAME` names in `line`, its comment (from `//`) left out.
fn named_modules(line: &str) -> Vec<String> {
    let code = line.split("//").next().unwrap_or("");
    code.match_indices("crate::")
        .map(|(i, _)| code[i + 7..].chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '_').collect())
        .filter(|name: &String| !name.is_empty())
        .collect()
}

#[test]
fn every_module_uses_only_the_layers_below_it() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    let rank = |m: &str| LAYERS.iter().position(|l| *l == m);
    let mut seen = std::collections::BTreeSet::new();
    let mut back_edges = Vec::new();
    for file in &files {
        let Some(module) = module_of(&src, file) else { continue };
        let Some(own) = rank(&module) else {
            panic!("{}: module `{module}` is not in LAYERS (add it where it belongs)", file.display())
        };
        seen.insert(module.clone());
        for (n, line) in std::fs::read_to_string(file).unwrap().lines().enumerate() {
            for used in named_modules(line) {
                if used == module {
                    continue;
                }
                match rank(&used) {
                    Some(r) if r < own => {}
                    _ => back_edges.push(format!("{}:{}: {module} uses {used}", file.display(), n + 1)),
                }
            }
        }
    }
    assert!(back_edges.is_empty(), "uses against the layers:\n{}", back_edges.join("\n"));
    let missing: Vec<_> = LAYERS.iter().filter(|l| !seen.contains(**l)).collect();
    assert!(missing.is_empty(), "LAYERS names modules that no longer exist: {missing:?}");
}

/// The checker itself: comments do not count, paths do.
#[test]
fn uses_are_read_from_code_not_comments() {
    assert_eq!(named_modules("use crate::io::{self, Document};"), vec!["io"]);
    assert_eq!(named_modules("let m = crate::mesh::Mesh::load(p)?; // see crate::render"), vec!["mesh"]);
    assert!(named_modules("/// [`crate::render::stage`] draws it").is_empty());
}
