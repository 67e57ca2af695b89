//! The docs name what the code writes (issue 30): the `prtkit…` names `docs/ibl.md` uses are
//! the ones the shader snippets of `ibl` define, language by language.
//!
//! `sh.glsl` and `sh.hlsl` define `prtkitIrradiance`, `sh.wgsl` defines `prtkit_irradiance`; a
//! page that called `prtkitIrradiance(n)` for all three sent a WGSL user to naga's "no definition
//! in scope". This test bakes a small map with the `ibl` binary, reads what each snippet defines
//! (the identifiers of its top-level lines: the generated files declare at the top level and use
//! their constant only inside the function) and checks every `prtkit…` or `PRTKIT_…` identifier
//! of `docs/ibl.md`: in a ```` ```glsl ````, ```` ```hlsl ```` or ```` ```wgsl ```` block it
//! must be defined in `sh.<language>`, anywhere else on the page (prose, the JavaScript and C++
//! examples) in at least one of the three. Each language must have a block that uses a name, so
//! that removing the examples does not pass silently. That the snippets themselves compile is
//! `tests/ibl.rs`'s business.

mod common;

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// The languages `ibl` writes a snippet in, each as `sh.<language>` and a fence's info string.
const LANGUAGES: [&str; 3] = ["glsl", "hlsl", "wgsl"];

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The identifiers of `text` that start with `prtkit` in any case and are longer than it (not
/// the project's name in "prtkit's" or `prtkit.ibl`).
fn prtkit_names(text: &str) -> impl Iterator<Item = &str> {
    text.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .filter(|word| word.len() > "prtkit".len() && word.to_ascii_lowercase().starts_with("prtkit"))
}

/// The `prtkit…` names a generated snippet defines: those on its top-level lines (not indented,
/// not comments).
fn definitions(snippet: &str) -> BTreeSet<String> {
    snippet
        .lines()
        .filter(|line| !line.starts_with(char::is_whitespace) && !line.starts_with("//"))
        .flat_map(prtkit_names)
        .map(str::to_owned)
        .collect()
}

/// The lines of a Markdown page, each with its number and the info string of the fenced block it
/// is in (`None` outside blocks; fences themselves are left out).
fn lines_in_blocks(page: &str) -> Vec<(usize, Option<&str>, &str)> {
    let mut out = Vec::new();
    let mut block: Option<&str> = None;
    for (i, line) in page.lines().enumerate() {
        match (line.trim_start().strip_prefix("```"), block) {
            (Some(info), None) => block = Some(info.trim()),
            (Some(_), Some(_)) => block = None,
            (None, _) => out.push((i + 1, block, line)),
        }
    }
    out
}

#[test]
fn docs_ibl_uses_the_names_the_ibl_snippets_define() {
    let dir = tempfile::tempdir().unwrap();
    let env = common::sky_pfm(dir.path(), 64, 32);
    let bake = dir.path().join("bake");
    common::cmd("ibl")
        .arg(&env)
        .arg("-o")
        .arg(&bake)
        .args(["--size", "16", "--min-size", "4", "--irradiance-size", "4", "--samples", "0", "-q"])
        .assert()
        .success();
    let defined: BTreeMap<&str, BTreeSet<String>> =
        LANGUAGES.iter().map(|&lang| (lang, definitions(&read(&bake.join(format!("sh.{lang}")))))).collect();

    let page = read(&Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/ibl.md"));
    let mut problems = Vec::new();
    let mut used_in = BTreeSet::new();
    for (line, block, text) in lines_in_blocks(&page) {
        let language = block.filter(|info| LANGUAGES.contains(info));
        for name in prtkit_names(text) {
            match language {
                Some(lang) if !defined[lang].contains(name) => problems.push(format!(
                    "docs/ibl.md:{line}: `{name}` in a {lang} block, but sh.{lang} defines {:?}",
                    defined[lang]
                )),
                Some(lang) => {
                    used_in.insert(lang);
                }
                None if !defined.values().any(|names| names.contains(name)) => problems
                    .push(format!("docs/ibl.md:{line}: `{name}` is defined by none of the snippets ({defined:?})")),
                None => {}
            }
        }
    }
    for lang in LANGUAGES.iter().filter(|lang| !used_in.contains(*lang)) {
        problems.push(format!("docs/ibl.md has no ```{lang} block calling sh.{lang}'s function"));
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}
