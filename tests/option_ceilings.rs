//! The option ceilings table of `docs/cli.md` behaves as documented: every row's example, run
//! in a directory with `sky.pfm` (64×32) and the project's `testdata/`, exits with the status the
//! row gives, says what the row quotes, and leaves no output.

mod common;

use std::path::Path;
use std::process::Command;

/// One row: the command, the exit status, a part of what it says on stderr.
struct Row {
    command: String,
    exit: i32,
    says: String,
}

/// The rows of the table under `## Option ceilings` in docs/cli.md (the last three columns).
fn rows() -> Vec<Row> {
    let doc = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/cli.md")).unwrap();
    let section = doc.split("## Option ceilings").nth(1).expect("docs/cli.md has an Option ceilings section");
    let code = |cell: &str| cell.trim().trim_matches('`').to_string();
    section
        .lines()
        .take_while(|l| !l.starts_with("## "))
        .filter(|l| l.starts_with('|') && !l.starts_with("| option") && !l.starts_with("| ---"))
        .map(|line| {
            let cells: Vec<&str> = line.trim_matches('|').split(" | ").collect();
            let n = cells.len();
            assert!(n >= 3, "a row of the ceilings table: {line}");
            let exit = cells[n - 2].trim().parse().unwrap_or_else(|_| panic!("exit status in {line}"));
            let row = Row { command: code(cells[n - 3]), exit, says: code(cells[n - 1]) };
            assert!(!row.command.is_empty() && !row.says.is_empty(), "a row without an example: {line}");
            row
        })
        .collect()
}

#[test]
fn every_row_of_the_option_ceilings_table_behaves_as_documented() {
    let dir = tempfile::tempdir().unwrap();
    common::sky_pfm(dir.path(), 64, 32);
    std::os::unix::fs::symlink(Path::new(env!("CARGO_MANIFEST_DIR")).join("testdata"), dir.path().join("testdata"))
        .unwrap();
    let before = common::entries(dir.path());
    let path = common::path_with_stages();
    let rows = rows();
    assert!(rows.len() >= 15, "{} rows", rows.len());
    for row in rows {
        let out = Command::new("bash")
            .arg("-c")
            .arg(&row.command)
            .current_dir(dir.path())
            .env("PATH", &path)
            .output()
            .unwrap();
        let stderr = common::stderr(&out);
        assert_eq!(out.status.code(), Some(row.exit), "{}: {stderr}", row.command);
        assert!(stderr.contains(&row.says), "{}: says {stderr:?}, not {:?}", row.command, row.says);
        assert!(!stderr.contains("panicked"), "{}: {stderr}", row.command);
        assert_eq!(common::entries(dir.path()), before, "{} left an output", row.command);
    }
}
