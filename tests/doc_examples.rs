//! Every documented example runs as written (issue 14, item 4), and writes only into its
//! document's own folder (issue 30).
//!
//! Each fenced ```` ```sh ```` block of `README.md` and `docs/**/*.md` is run by `bash` with
//! `set -euo pipefail`, as a user would paste it, in a fresh scratch directory that holds what a
//! clone holds: `testdata/` (the project's, copied), `examples/bake/`, `target/release/` (the
//! binaries this test was built with) and `../shared/testdata` (the external data, when present).
//! The binaries are on `PATH`, as `docs/cli.md` says to put them. A block passes when it exits 0
//! without a panic and leaves nothing outside its document's folder; its outputs are the stages'
//! own business (their tests check the numbers).
//!
//! **The folder rule.** A user pastes the examples into a clone, one document after another, so
//! each document writes only under `out/<name>/` (`/out/` is gitignored): `<name>` is the
//! document's path without `docs/` and `.md`, lower case, `/` as `-` (`README.md` → `out/readme/`,
//! `docs/ibl.md` → `out/ibl/`, `docs/formats/ibl.md` → `out/formats-ibl/`). Then no two documents
//! share a folder, none overwrites another's outputs or finds another's bake in its way, and the
//! clone stays clean (`git status` shows nothing). The one exception, in [`OWN_FOLDERS`], is
//! `docs/bake.md`, whose Makefile writes into its own gitignored `examples/bake/out/`. After each
//! block the scratch directory is listed (links not followed): every file or directory the block
//! created outside its document's folder (and not a parent of it, like `out/` itself) fails the
//! test, naming the document, the block's line and the stray paths, and the folder of the
//! document that owns a stray path in `out/`, if one does. `testdata/` is copied rather than
//! linked so that a block writing into it is caught too.
//!
//! Why not `trycmd`: the examples are shell (variables, pipes into `jq`, `|| echo`, redirects,
//! `printf > file`), which `trycmd` runs without a shell; rewriting them in its format would test
//! something other than what a reader copies.
//!
//! Not run, each for the reason in [`NOT_RUN`]: lines that build or test the project itself
//! (the test runs on the built binaries, and `cargo test` inside `cargo test` would recurse).
//! Run only with `PRTKIT_DOC_EXAMPLES=all`: the few examples in [`SLOW`], which take minutes
//! (CI's whole suite must stay under 30 minutes). A block that calls a tool not on `PATH` (`jq`,
//! `cmft`) or reads `../shared/testdata` when it is absent is skipped with a message.

mod common;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// Lines of examples that are not run: (the line's start, why).
const NOT_RUN: &[(&str, &str)] = &[
    ("cargo build", "the test runs on the binaries cargo built for it"),
    ("cargo test", "the test suite itself (it would recurse)"),
    ("scripts/demo.sh", "the demo builds the project; CI runs it on its own"),
];

/// Examples that take minutes, run only with `PRTKIT_DOC_EXAMPLES=all`: (file, a part of the
/// line, what it costs). Later lines of their blocks must not need their outputs.
const SLOW: &[(&str, &str, &str)] = &[
    (
        "docs/prefilter.md",
        "--shrm $out/micro.exr",
        "reflection maps of views of a microfacet SHRM under the texel rule: > 2 min for one view at 256x128",
    ),
    ("docs/prefilter.md", "--icosahedral $out/ico/", "32 view maps of a microfacet BRDF under the texel rule: > 2 min"),
];

/// Documents whose examples write somewhere other than `out/<name>/`: (document, its folder, why).
const OWN_FOLDERS: &[(&str, &str, &str)] = &[(
    "docs/bake.md",
    "examples/bake/out",
    "the Makefile writes beside itself (gitignored), where tests/bake.rs checks its targets",
)];

/// Tools an example may call that are not prtkit's: a block calling one that is missing is skipped.
const EXTERNAL_TOOLS: &[&str] = &["jq", "cmft", "make"];

/// One fenced block: where it is and its text.
struct Example {
    file: PathBuf,
    line: usize,
    script: String,
}

fn repo() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The Markdown files whose examples are promised to run: the README and everything in docs/.
fn documents() -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        let mut entries: Vec<_> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
        entries.sort();
        for path in entries {
            if path.is_dir() {
                walk(&path, out);
            } else if path.extension().is_some_and(|e| e == "md") {
                out.push(path);
            }
        }
    }
    let mut files = vec![repo().join("README.md")];
    walk(&repo().join("docs"), &mut files);
    files
}

/// The folder `document` (relative to the repository) writes into: `out/<name>/` as the module
/// doc says, or its entry in [`OWN_FOLDERS`]. Relative to the directory the examples run in.
fn own_folder(document: &Path) -> PathBuf {
    if let Some((_, folder, _)) = OWN_FOLDERS.iter().find(|(d, _, _)| document == Path::new(d)) {
        return PathBuf::from(folder);
    }
    let name = document.strip_prefix("docs").unwrap_or(document).with_extension("");
    Path::new("out").join(name.to_string_lossy().to_lowercase().replace('/', "-"))
}

/// The ```` ```sh ```` blocks of `file`, with the line of their opening fence.
fn examples(file: &Path) -> Vec<Example> {
    let text = std::fs::read_to_string(file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
    let mut out = Vec::new();
    let mut open: Option<(usize, String)> = None;
    for (i, line) in text.lines().enumerate() {
        let fence = line.trim_start().strip_prefix("```");
        match (&mut open, fence) {
            (None, Some(info)) if info.trim() == "sh" => open = Some((i + 1, String::new())),
            (None, Some(_)) => open = Some((0, String::new())), // a block of another language
            (Some((start, script)), Some(_)) => {
                if *start > 0 {
                    let script = runnable(file, script);
                    out.push(Example { file: file.to_owned(), line: *start, script });
                }
                open = None;
            }
            (Some((_, script)), None) => {
                *script += line;
                *script += "\n";
            }
            (None, None) => {}
        }
    }
    out
}

/// `block` with the lines that are not run replaced by a comment saying why. A line ending in
/// `\\` continues on the next: the two are one command.
fn runnable(file: &Path, block: &str) -> String {
    let all = std::env::var("PRTKIT_DOC_EXAMPLES").is_ok_and(|v| v == "all");
    let file = file.strip_prefix(repo()).unwrap_or(file);
    let mut out = String::new();
    let mut command = String::new();
    for line in block.lines() {
        command += line;
        command += "\n";
        if line.ends_with('\\') {
            continue;
        }
        let start = command.trim_start();
        let not_run = NOT_RUN.iter().find(|(s, _)| start.starts_with(s)).map(|(_, why)| *why);
        let slow = SLOW.iter().find(|(f, part, _)| !all && file == Path::new(f) && command.contains(part));
        match (not_run, slow) {
            (Some(why), _) => out += &format!("# not run: {why}\n"),
            (None, Some((_, _, cost))) => {
                eprintln!("{}: skipped (slow: {cost}; PRTKIT_DOC_EXAMPLES=all runs it)", file.display());
                out += &format!("# slow, not run: {cost}\n");
            }
            (None, None) => out += &command,
        }
        command.clear();
    }
    out + &command
}

fn on_path(tool: &str) -> bool {
    std::env::var_os("PATH").is_some_and(|path| std::env::split_paths(&path).any(|dir| dir.join(tool).is_file()))
}

/// Why `example` cannot run on this machine, if it cannot.
fn skip_reason(example: &Example, shared: &Path) -> Option<String> {
    let words: Vec<&str> = example
        .script
        .lines()
        .filter(|l| !l.trim_start().starts_with('#'))
        .flat_map(|l| l.split(|c: char| c.is_whitespace() || c == '|' || c == '(' || c == ';'))
        .collect();
    if let Some(tool) = EXTERNAL_TOOLS.iter().find(|t| words.contains(t) && !on_path(t)) {
        return Some(format!("`{tool}` is not on PATH"));
    }
    if example.script.contains("../shared/testdata") && !shared.join("testdata").is_dir() {
        return Some(format!("{} is absent", shared.join("testdata").display()));
    }
    None
}

/// A scratch directory laid out like a clone: `work/` (the current directory of the example)
/// with `testdata` and `target/release`, beside `shared` (what `../shared` means there).
fn scratch(root: &Path, bin_dir: &Path, shared: &Path) -> PathBuf {
    use std::os::unix::fs::symlink;
    let work = root.join("work");
    std::fs::create_dir_all(work.join("target")).unwrap();
    symlink(bin_dir, work.join("target/release")).unwrap();
    // Copied, not linked: docs/bake.md's make writes its outputs beside the Makefile, and a
    // block writing into testdata/ must be seen by [`tree`], not land in the clone.
    common::copy_tree(&repo().join("testdata"), &work.join("testdata"), &[]);
    common::copy_tree(&repo().join("examples/bake"), &work.join("examples/bake"), &["out"]);
    if shared.is_dir() {
        symlink(shared, root.join("shared")).unwrap();
    }
    work
}

/// Every path in the scratch directory `root`, as the example sees it: relative to `root/work`
/// (its current directory), `../…` beside it. Links are listed, not followed.
fn tree(root: &Path) -> BTreeSet<PathBuf> {
    fn walk(dir: &Path, shown: &Path, out: &mut BTreeSet<PathBuf>) {
        for entry in std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
            let entry = entry.unwrap();
            let path = shown.join(entry.file_name());
            if entry.file_type().unwrap().is_dir() {
                walk(&entry.path(), &path, out);
            }
            out.insert(path);
        }
    }
    let mut paths = BTreeSet::new();
    walk(&root.join("work"), Path::new(""), &mut paths);
    for entry in std::fs::read_dir(root).unwrap().map(|e| e.unwrap()) {
        if entry.file_name() != "work" {
            walk(&entry.path(), &Path::new("..").join(entry.file_name()), &mut paths);
        }
    }
    paths
}

/// What a block created (in `after`, not in `before`) outside `folder`, the parents of `folder`
/// aside. A created directory outside it stands for everything in it.
fn strays(before: &BTreeSet<PathBuf>, after: &BTreeSet<PathBuf>, folder: &Path) -> Vec<PathBuf> {
    let outside = |p: &Path| !p.starts_with(folder) && !folder.starts_with(p);
    let created: BTreeSet<&PathBuf> = after.difference(before).filter(|p| outside(p)).collect();
    let in_created = |p: &Path| p.parent().is_some_and(|parent| created.contains(&parent.to_path_buf()));
    created.iter().filter(|p| !in_created(p)).map(|p| p.to_path_buf()).collect()
}

/// `strays` as a list for a message, each in another document's folder followed by that document.
fn describe(strays: &[PathBuf], owners: &BTreeMap<PathBuf, String>) -> String {
    let describe_one = |path: &PathBuf| {
        let owner = owners.iter().find(|(folder, _)| path.starts_with(folder));
        match owner {
            Some((_, document)) => format!("{} (in {document}'s folder)", path.display()),
            None => path.display().to_string(),
        }
    };
    strays.iter().map(describe_one).collect::<Vec<_>>().join(", ")
}

#[test]
fn every_documented_example_runs_as_written() {
    let bin_dir = common::bin_dir();
    let shared = repo().join("../shared");
    let path = common::path_with_stages();
    let documents = documents();
    let mut owners = BTreeMap::new();
    for file in &documents {
        let document = file.strip_prefix(repo()).unwrap();
        let folder = own_folder(document);
        if let Some(other) = owners.insert(folder.clone(), document.display().to_string()) {
            panic!("{} and {other} would share the folder {}", document.display(), folder.display());
        }
    }
    let mut failures = Vec::new();
    let mut ran = 0;
    for file in documents {
        let folder = own_folder(file.strip_prefix(repo()).unwrap());
        for example in examples(&file) {
            let name = format!("{}:{}", example.file.strip_prefix(repo()).unwrap().display(), example.line);
            if let Some(why) = skip_reason(&example, &shared) {
                eprintln!("{name}: skipped: {why}");
                continue;
            }
            let root = tempfile::tempdir().unwrap();
            let work = scratch(root.path(), &bin_dir, &shared);
            let before = tree(root.path());
            let start = Instant::now();
            let output = Command::new("bash")
                .arg("-c")
                .arg(format!("set -euo pipefail\n{}", example.script))
                .current_dir(&work)
                .env("PATH", &path)
                .output()
                .unwrap();
            ran += 1;
            let stderr = String::from_utf8_lossy(&output.stderr);
            eprintln!("{name}: exit {:?} in {:.1} s", output.status.code(), start.elapsed().as_secs_f64());
            if !output.status.success() || stderr.contains("panicked") {
                failures.push(format!("{name}: exit {:?}\n{}", output.status.code(), stderr.trim_end()));
            }
            let strays = strays(&before, &tree(root.path()), &folder);
            if !strays.is_empty() {
                let folder = folder.display();
                let strays = describe(&strays, &owners);
                failures.push(format!("{name}: left files outside the document's folder {folder}/: {strays}"));
            }
        }
    }
    assert!(ran > 0, "no examples found");
    assert!(failures.is_empty(), "{} of {ran} examples failed:\n\n{}", failures.len(), failures.join("\n\n"));
}
